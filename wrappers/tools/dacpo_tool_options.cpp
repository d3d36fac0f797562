/* SPDX-License-Identifier: BSD-3-Clause */
/* The command line of the pcl_dacpo_* tools (dacpo_tool_options.h): file
 * arguments by extension, the unknown-option check with its typo hints, help
 * text wrapping and strict number parsing. */
#include "dacpo_tool_options.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace dacpo_tool {

std::string
extension(const std::string& path)
{
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || path.find('/', dot) != std::string::npos)
    return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  return ext;
}

std::vector<std::string>
fileArguments(int argc, char** argv, const std::vector<const char*>& value_options)
{
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string ext = extension(argv[i]);
    if (ext != ".pcd" && ext != ".ply")
      continue;
    if (i > 1 &&
        std::any_of(value_options.begin(), value_options.end(), [&](const char* o) {
          return std::strcmp(argv[i - 1], o) == 0;
        }))
      continue;
    files.emplace_back(argv[i]);
  }
  return files;
}

std::size_t
editDistance(const std::string& a, const std::string& b)
{
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j)
    row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min(
          {row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] != b[j - 1] ? 1u : 0u)});
      diag = up;
    }
  }
  return row[b.size()];
}

bool
checkArguments(int argc,
               char** argv,
               const std::vector<const char*>& switches,
               const std::vector<const char*>& valued,
               std::string& error)
{
  auto in = [](const std::vector<const char*>& list, const std::string& a) {
    return std::any_of(list.begin(), list.end(), [&](const char* o) { return a == o; });
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (in(valued, a)) {
      ++i; /* its value (a missing one is the option parser's to report) */
      continue;
    }
    if (in(switches, a))
      continue;
    if (!a.empty() && a[0] == '-') {
      std::string best;
      std::size_t best_d = 3; /* suggest only close names */
      const std::size_t first = a.find_first_not_of('-');
      const std::string bare =
          first == std::string::npos ? std::string() : a.substr(first);
      for (const std::vector<const char*>* list : {&switches, &valued})
        for (const char* o : *list) {
          const std::size_t d =
              std::min(editDistance(a, o), editDistance("-" + bare, o));
          if (d < best_d) {
            best_d = d;
            best = o;
          }
        }
      error = "unknown option '" + a + "'" +
              (best.empty() ? std::string() : "; did you mean '" + best + "'?") +
              " (-h lists the options)";
      return false;
    }
    const std::string ext = extension(a);
    if (ext != ".pcd" && ext != ".ply") {
      error = "unexpected argument '" + a + "': files must be .pcd or .ply";
      return false;
    }
  }
  return true;
}

std::string
wrapHelp(const std::string& text, std::size_t width)
{
  std::string out;
  std::size_t line_start = 0;
  for (char c : text) {
    out += c;
    if (c == '\n') {
      line_start = out.size();
      continue;
    }
    if (out.size() - line_start > width) {
      const std::size_t space = out.rfind(' ');
      if (space != std::string::npos && space > line_start) {
        out[space] = '\n';
        line_start = space + 1;
      }
    }
  }
  return out;
}

bool
toUnsigned(const std::string& s, std::uint64_t& v)
{
  char* end = nullptr;
  errno = 0;
  const unsigned long long r = std::strtoull(s.c_str(), &end, 10);
  if (s.empty() || *end || errno || s[0] == '-')
    return false;
  v = r;
  return true;
}

bool
toDouble(const std::string& s, double& v)
{
  char* end = nullptr;
  errno = 0;
  const double r = std::strtod(s.c_str(), &end);
  if (s.empty() || *end || errno || !std::isfinite(r))
    return false;
  v = r;
  return true;
}

} // namespace dacpo_tool
