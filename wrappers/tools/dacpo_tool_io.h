/* SPDX-License-Identifier: BSD-3-Clause */
/* Shared by the pcl_dacpo_* tools: load/save pcl::PCLPointCloud2 by extension
 * with clear errors, read named float fields of any numeric type, strict number
 * parsing of options. Header-only, tools only (not installed). */
#pragma once

#include "dacpo_cleanup.h"
#include "dacpo_paths.h"
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/point_types.h>

#include <sys/stat.h>

#include <algorithm>
#include <exception>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <limits>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace dacpo_tool {

/** Lower-case extension including the dot (".pcd"), or "". */
inline std::string
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

/** Positional .pcd/.ply arguments in command-line order; values of the options
 *  named in \a value_options (e.g. "-colored out.pcd") are not positional. */
inline std::vector<std::string>
fileArguments(int argc, char** argv, const std::vector<const char*>& value_options = {})
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

/** Edit distance (insert, delete, substitute) of two short strings. */
inline std::size_t
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

/** Every argument must be a known switch, a known option followed by its
 *  value, or a .pcd/.ply file: a typo ("-frobnicate 3", "--k 5") must not run
 *  silently with defaults. On failure returns false with a message naming the
 *  argument and, when one is close, the option meant. */
inline bool
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

/** The class of a pointer to member (Options for std::string Options::*). */
template <typename Member>
struct MemberOf;
template <typename Class, typename T>
struct MemberOf<T Class::*> {
  using type = Class;
};

/** Setter of an OptionSpec for an option whose value is kept as given (the tool
 *  checks it afterwards): setText<&Options::field>. */
template <auto Field>
bool
setText(typename MemberOf<decltype(Field)>::type& o, const std::string& s, std::string&)
{
  o.*Field = s;
  return true;
}

/** Setter of an OptionSpec for a switch: setFlag<&Options::field>. */
template <auto Field>
bool
setFlag(typename MemberOf<decltype(Field)>::type& o, const std::string&, std::string&)
{
  o.*Field = true;
  return true;
}

/** One command-line option of a tool's table. The help text (printOptionTable),
 *  the parser (applyOptions) and the unknown-option check (checkOptionTable) all
 *  read the tool's table, so an option is named once. */
template <typename Options, typename Defaults>
struct OptionSpec {
  const char* name;
  const char* arg;  /* nullptr: a switch; else the value's placeholder in -h */
  const char* help; /* '\n' starts a continuation line */
  /* the default shown in -h; nullptr: none */
  std::string (*shown)(const Defaults&);
  /* sets the options from the value (a switch gets ""); false + error */
  bool (*apply)(Options&, const std::string&, std::string&);
};

/** The table entry named \a name, or nullptr. */
template <typename Spec, std::size_t N>
const Spec*
findOption(const Spec (&table)[N], const char* name)
{
  for (const Spec& spec : table)
    if (std::strcmp(spec.name, name) == 0)
      return &spec;
  return nullptr;
}

/** The switches (\a with_value false) or the options that take a value, for
 *  checkArguments and fileArguments. */
template <typename Spec, std::size_t N>
std::vector<const char*>
optionNames(const Spec (&table)[N], bool with_value)
{
  std::vector<const char*> names;
  for (const Spec& spec : table)
    if ((spec.arg != nullptr) == with_value)
      names.push_back(spec.name);
  return names;
}

/** checkArguments with the switches and valued options of \a table. */
template <typename Spec, std::size_t N>
bool
checkOptionTable(const Spec (&table)[N], int argc, char** argv, std::string& error)
{
  return checkArguments(
      argc, argv, optionNames(table, false), optionNames(table, true), error);
}

/** Applies the options in command-line order: a repeated option keeps its last
 *  value; a missing value or a setter's refusal is printed, then false. */
template <typename Spec, std::size_t N, typename Options>
bool
applyOptions(const Spec (&table)[N], int argc, char** argv, Options& o)
{
  for (int i = 1; i < argc; ++i) {
    const Spec* spec = findOption(table, argv[i]);
    if (spec == nullptr)
      continue; /* a file (unknown options were rejected before) */
    std::string value, error;
    if (spec->arg != nullptr) {
      if (i + 1 >= argc || argv[i + 1][0] == '\0') {
        const bool file = std::strncmp(spec->arg, "F.", 2) == 0;
        pcl::console::print_error("Error: %s needs a %s (%s)\n",
                                  spec->name,
                                  file ? "file name" : "value",
                                  spec->arg);
        return false;
      }
      value = argv[++i];
    }
    if (!spec->apply(o, value, error)) {
      pcl::console::print_error("Error: %s %s\n", spec->name, error.c_str());
      return false;
    }
  }
  return true;
}

/** Help lines wrap at this many characters (the parameter table's one-line
 *  docs; hand-written helps break their own lines with '\n'). */
constexpr std::size_t kHelpWidth = 56;

/** \a text with every line longer than \a width broken at its last space
 *  before that width. */
inline std::string
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

/** The options part of -h, one entry per option: 21 spaces, the name and the
 *  value's placeholder padded to \a head_width, " = ", the help with its
 *  continuation lines indented by \a indent, and the default if shown. */
template <typename Spec, std::size_t N, typename Defaults>
void
printOptionTable(const Spec (&table)[N],
                 const Defaults& defaults,
                 std::size_t head_width,
                 std::size_t indent)
{
  for (const Spec& spec : table) {
    std::string head = spec.name;
    if (spec.arg)
      head += std::string(" ") + spec.arg;
    if (head.size() < head_width)
      head.resize(head_width, ' ');
    std::string text = wrapHelp(spec.help, kHelpWidth);
    for (std::size_t at = text.find('\n'); at != std::string::npos;
         at = text.find('\n', at + 1))
      text.insert(at + 1, indent, ' ');
    pcl::console::print_info(
        "                     %s = %s", head.c_str(), text.c_str());
    if (spec.shown) {
      pcl::console::print_info(" (default: ");
      pcl::console::print_value("%s", spec.shown(defaults).c_str());
      pcl::console::print_info(")");
    }
    pcl::console::print_info("\n");
  }
}

namespace detail {

/** A whole token that strtod takes (numbers, nan, inf). */
inline bool
isNumber(const std::string& t)
{
  if (t.empty())
    return false;
  char* end = nullptr;
  errno = 0;
  (void)std::strtod(t.c_str(), &end);
  return end == t.c_str() + t.size();
}

inline std::vector<std::string>
tokens(const std::string& line)
{
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i])))
      ++i;
    std::size_t j = i;
    while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j])))
      ++j;
    if (j > i)
      out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

/** \a s with bytes outside printable ASCII shown as '?' (for messages). */
inline std::string
printable(std::string s)
{
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126)
      c = '?';
  return s;
}

/** Reads one '\n'-terminated line (without it); false at end of file. */
inline bool
readLine(std::FILE* f, std::string& line, std::size_t max_len = 1 << 20)
{
  line.clear();
  int c;
  while ((c = std::fgetc(f)) != EOF) {
    if (c == '\n')
      return true;
    if (line.size() < max_len)
      line.push_back(static_cast<char>(c));
  }
  return !line.empty();
}

inline bool
parseCount(const std::string& t, unsigned long long& v)
{
  if (t.empty() || t.find_first_not_of("0123456789") != std::string::npos ||
      t.size() > 19)
    return false;
  v = std::strtoull(t.c_str(), nullptr, 10);
  return true;
}

/** Where a file check stands, and its error message: "'path' is not a valid
 *  KIND file: line N: what". */
struct FileCheck {
  const std::string& path;
  const char* kind; /* "PCD" or "PLY" */
  std::string& error;
  std::size_t lineno = 0;

  bool
  bad(const std::string& what)
  {
    error = "'" + path + "' is not a valid " + kind + " file: line " +
            std::to_string(lineno) + ": " + printable(what);
    return false;
  }
};

/** What a PCD header declares. */
struct PcdHeader {
  std::vector<std::string> fields, size, type, count;
  unsigned long long width = 0, height = 0, points = 0;
  bool have_width = false, have_height = false, have_points = false;
  std::string data; /* ascii, binary or binary_compressed */
};

/** The header lines up to and including DATA. */
inline bool
readPcdHeader(std::FILE* f, FileCheck& fc, PcdHeader& h)
{
  std::string line;
  while (h.data.empty()) {
    if (!readLine(f, line, 4096))
      return fc.bad("the header ends before its DATA line");
    ++fc.lineno;
    if (line.find('\0') != std::string::npos)
      return fc.bad("binary bytes in the header");
    const std::vector<std::string> t = tokens(line);
    if (t.empty() || t[0][0] == '#')
      continue;
    const std::string& key = t[0];
    const std::vector<std::string> rest(t.begin() + 1, t.end());
    if (key == "VERSION" || key == "VIEWPOINT")
      continue;
    else if (key == "FIELDS" || key == "COLUMNS")
      h.fields = rest;
    else if (key == "SIZE")
      h.size = rest;
    else if (key == "TYPE")
      h.type = rest;
    else if (key == "COUNT")
      h.count = rest;
    else if (key == "WIDTH" && rest.size() == 1 && parseCount(rest[0], h.width))
      h.have_width = true;
    else if (key == "HEIGHT" && rest.size() == 1 && parseCount(rest[0], h.height))
      h.have_height = true;
    else if (key == "POINTS" && rest.size() == 1 && parseCount(rest[0], h.points))
      h.have_points = true;
    else if (key == "DATA" && rest.size() == 1)
      h.data = rest[0];
    else
      return fc.bad("unexpected '" + line.substr(0, 60) + "'");
  }
  return true;
}

/** The fields' sizes, types and counts, and WIDTH x HEIGHT = POINTS; bytes and
 *  values per point. */
inline bool
checkPcdLayout(FileCheck& fc,
               PcdHeader& h,
               unsigned long long& point_size,
               unsigned long long& values)
{
  if (h.fields.empty() || h.size.size() != h.fields.size() ||
      h.type.size() != h.fields.size())
    return fc.bad("FIELDS, SIZE and TYPE must list the same number of entries");
  if (h.count.empty())
    h.count.assign(h.fields.size(), "1");
  if (h.count.size() != h.fields.size())
    return fc.bad("COUNT must list one entry per field");
  point_size = 0;
  values = 0;
  for (std::size_t i = 0; i < h.fields.size(); ++i) {
    unsigned long long sz = 0, c = 0;
    if (!parseCount(h.size[i], sz) || (sz != 1 && sz != 2 && sz != 4 && sz != 8))
      return fc.bad("SIZE of field '" + h.fields[i] + "' must be 1, 2, 4 or 8");
    if (h.type[i] != "F" && h.type[i] != "I" && h.type[i] != "U")
      return fc.bad("TYPE of field '" + h.fields[i] + "' must be F, I or U");
    if (!parseCount(h.count[i], c) || c == 0 || c > 100000)
      return fc.bad("COUNT of field '" + h.fields[i] + "' must be a positive integer");
    point_size += sz * c;
    values += c;
  }
  if (!h.have_width || !h.have_points)
    return fc.bad("WIDTH and POINTS are required");
  if (!h.have_height)
    h.height = 1;
  if (h.width > (1ull << 40) || h.height > (1ull << 40) ||
      h.width * h.height != h.points)
    return fc.bad("WIDTH x HEIGHT differs from POINTS");
  return true;
}

/** binary_compressed: the two sizes in front of the data against the header and
 *  the file. */
inline bool
checkPcdCompressed(std::FILE* f,
                   FileCheck& fc,
                   long long data_bytes,
                   unsigned long long points,
                   unsigned long long point_size)
{
  unsigned char sizes[8];
  if (points > 0 && std::fread(sizes, 1, 8, f) != 8)
    return fc.bad("compressed data is missing");
  if (points == 0)
    return true;
  const unsigned long long packed =
      sizes[0] | sizes[1] << 8 | sizes[2] << 16 | (unsigned long long)sizes[3] << 24;
  const unsigned long long unpacked =
      sizes[4] | sizes[5] << 8 | sizes[6] << 16 | (unsigned long long)sizes[7] << 24;
  if (unpacked != points * point_size)
    return fc.bad("compressed data holds " + std::to_string(unpacked) +
                  " bytes, the header needs " + std::to_string(points * point_size));
  if ((unsigned long long)(data_bytes - 8) < packed)
    return fc.bad("compressed data is truncated");
  /* LZF expands at most ~100x: a larger claim is corrupt (and would be
   * allocated before anything is read) */
  if (unpacked > 128 * packed + 4096)
    return fc.bad("compressed data claims " + std::to_string(unpacked) +
                  " bytes from " + std::to_string(packed));
  return true;
}

/** ascii: one line of `values` numbers per point. */
inline bool
checkPcdAscii(std::FILE* f,
              FileCheck& fc,
              long long data_bytes,
              unsigned long long points,
              unsigned long long values)
{
  if (points > (unsigned long long)std::max(0LL, data_bytes) / (2 * values))
    return fc.bad("the header claims " + std::to_string(points) +
                  " points, more than the file's ASCII data can hold");
  std::string line;
  for (unsigned long long p = 0; p < points; ++p) {
    if (!readLine(f, line))
      return fc.bad("ASCII data is truncated: it ends after " + std::to_string(p) +
                    " of " + std::to_string(points) + " points");
    ++fc.lineno;
    const std::vector<std::string> t = tokens(line);
    if (t.size() != values)
      return fc.bad("expected " + std::to_string(values) + " values, found " +
                    std::to_string(t.size()));
    for (const std::string& v : t)
      if (!isNumber(v))
        return fc.bad("'" + v.substr(0, 40) + "' is not a number");
  }
  return true;
}

/** The PCD header and, for ASCII data, every value: PCL 1.13's reader
 *  crashes on files that are not PCD and turns words into NaN. */
inline bool
checkPcd(std::FILE* f, long long file_size, const std::string& path, std::string& error)
{
  FileCheck fc{path, "PCD", error};
  PcdHeader h;
  unsigned long long point_size = 0, values = 0;
  if (!readPcdHeader(f, fc, h) || !checkPcdLayout(fc, h, point_size, values))
    return false;
  const long long header_end = std::ftell(f);
  const long long data_bytes = file_size - header_end;
  if (h.data != "ascii") {
    /* PCL 1.13 throws an uncaught std::length_error (abort) when binary data
     * starts with the bytes of the old header keyword COLUMNS (found by
     * fuzzing) */
    char head[7] = {0};
    const std::size_t got = std::fread(head, 1, sizeof(head), f);
    if (got == sizeof(head) && std::memcmp(head, "COLUMNS", sizeof(head)) == 0)
      return fc.bad(
          "the binary data starts with 'COLUMNS', which PCL's reader takes for a "
          "header line");
    std::fseek(f, header_end, SEEK_SET);
  }
  if (h.data == "binary") {
    if (h.points > 0 && (unsigned long long)data_bytes < h.points * point_size)
      return fc.bad("binary data is truncated: " + std::to_string(h.points) +
                    " points of " + std::to_string(point_size) + " bytes need " +
                    std::to_string(h.points * point_size) + " bytes, the file holds " +
                    std::to_string(data_bytes));
    return true;
  }
  if (h.data == "binary_compressed")
    return checkPcdCompressed(f, fc, data_bytes, h.points, point_size);
  if (h.data == "ascii")
    return checkPcdAscii(f, fc, data_bytes, h.points, values);
  return fc.bad("DATA must be ascii, binary or binary_compressed, got '" + h.data +
                "'");
}

/** Bytes of a PLY scalar type, 0 if unknown. */
inline unsigned
plyTypeSize(const std::string& t)
{
  static const char* const one[] = {"char", "uchar", "int8", "uint8"};
  static const char* const two[] = {"short", "ushort", "int16", "uint16"};
  static const char* const four[] = {
      "int", "uint", "float", "int32", "uint32", "float32"};
  static const char* const eight[] = {"double", "float64"};
  for (const char* x : one)
    if (t == x)
      return 1;
  for (const char* x : two)
    if (t == x)
      return 2;
  for (const char* x : four)
    if (t == x)
      return 4;
  for (const char* x : eight)
    if (t == x)
      return 8;
  return 0;
}

/** An element of a PLY header, as far as the checks need it. */
struct PlyCheckElement {
  unsigned long long count;
  std::vector<bool> is_list;
  unsigned long long min_bytes; /* binary: smallest record */
};

/** The header after its 'ply' line, through end_header: the format and the
 *  elements. */
inline bool
readPlyHeader(std::FILE* f,
              FileCheck& fc,
              std::vector<PlyCheckElement>& elements,
              std::string& format)
{
  std::string line;
  for (;;) {
    if (!readLine(f, line, 4096))
      return fc.bad("the header ends before 'end_header'");
    ++fc.lineno;
    const std::vector<std::string> t = tokens(line);
    if (t.empty())
      continue;
    if (t[0] == "end_header")
      return true;
    if (t[0] == "format") {
      if (t.size() != 3 || (t[1] != "ascii" && t[1] != "binary_little_endian" &&
                            t[1] != "binary_big_endian"))
        return fc.bad(
            "format must be ascii, binary_little_endian or binary_big_endian");
      format = t[1];
    }
    else if (t[0] == "element") {
      PlyCheckElement e{0, {}, 0};
      if (t.size() != 3 || !parseCount(t[2], e.count))
        return fc.bad("'element NAME COUNT' expected");
      elements.push_back(e);
    }
    else if (t[0] == "property") {
      if (elements.empty())
        return fc.bad("a property before any element");
      const bool list = t.size() == 5 && t[1] == "list";
      if (list ? (plyTypeSize(t[2]) == 0 || plyTypeSize(t[3]) == 0)
               : (t.size() != 3 || plyTypeSize(t[1]) == 0))
        return fc.bad("unknown property '" + line.substr(0, 60) + "'");
      elements.back().is_list.push_back(list);
      elements.back().min_bytes += plyTypeSize(list ? t[2] : t[1]);
    }
    else if (t[0] != "comment" && t[0] != "obj_info")
      return fc.bad("unexpected '" + line.substr(0, 60) + "'");
  }
}

/** Every record takes at least this many bytes: binary, its scalars (a list at
 *  least its length); ASCII, one character and a separator per value. The
 *  data_bytes after the header must hold them all. */
inline bool
checkPlyCounts(FileCheck& fc,
               const std::vector<PlyCheckElement>& elements,
               const std::string& format,
               long long data_bytes)
{
  unsigned long long need = 0;
  for (const PlyCheckElement& e : elements) {
    const unsigned long long per = format == "ascii"
                                       ? 2 * std::max<std::size_t>(1, e.is_list.size())
                                       : e.min_bytes;
    if (per > 0 &&
        e.count > static_cast<unsigned long long>(std::max(0LL, data_bytes)) / per)
      return fc.bad("the header claims " + std::to_string(e.count) +
                    " records, more than the file's " + std::to_string(data_bytes) +
                    " data bytes can hold");
    need += e.count * per;
  }
  if (need > static_cast<unsigned long long>(std::max(0LL, data_bytes)))
    return fc.bad("the data is shorter than the header says");
  return true;
}

/** ASCII data: every record of every element holds exactly its values (list
 *  lengths included), all numbers. */
inline bool
checkPlyAscii(std::FILE* f, FileCheck& fc, const std::vector<PlyCheckElement>& elements)
{
  std::string line;
  for (const PlyCheckElement& e : elements)
    for (unsigned long long r = 0; r < e.count; ++r) {
      if (!readLine(f, line))
        return fc.bad("the data ends early");
      ++fc.lineno;
      const std::vector<std::string> t = tokens(line);
      std::size_t k = 0;
      for (bool list : e.is_list) {
        unsigned long long n = 1;
        if (list) {
          if (k >= t.size() || !parseCount(t[k], n))
            return fc.bad("a list length is missing or not a count");
          ++k;
        }
        for (unsigned long long j = 0; j < n; ++j, ++k) {
          if (k >= t.size())
            return fc.bad("too few values");
          if (!isNumber(t[k]))
            return fc.bad("'" + t[k].substr(0, 40) + "' is not a number");
        }
      }
      if (k != t.size())
        return fc.bad("too many values");
    }
  return true;
}

/** PLY header sanity (format, property types, element counts the file can
 *  hold: PCL 1.13 allocates what the header claims before reading, so a
 *  corrupt count exhausted memory), and for ASCII PLY every value of every
 *  element line must be a number (PCL 1.13 turns words into NaN). */
inline bool
checkPly(std::FILE* f, long long file_size, const std::string& path, std::string& error)
{
  FileCheck fc{path, "PLY", error};
  std::string line;
  std::vector<PlyCheckElement> elements;
  std::string format;
  if (!readLine(f, line, 64) ||
      (++fc.lineno, tokens(line) != std::vector<std::string>{"ply"}))
    return fc.bad("the file does not start with 'ply'");
  if (!readPlyHeader(f, fc, elements, format))
    return false;
  if (format.empty())
    return fc.bad("no format line");
  if (!checkPlyCounts(fc, elements, format, file_size - std::ftell(f)))
    return false;
  return format != "ascii" || checkPlyAscii(f, fc, elements);
}

} // namespace detail

/** Checks the file's own structure before PCL parses it (see detail::checkPcd
 *  and detail::checkPly). */
inline bool
checkCloudFile(const std::string& path, long long file_size, std::string& error)
{
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    error = "cannot open '" + path + "': " + std::strerror(errno);
    return false;
  }
  const bool ok = extension(path) == ".pcd"
                      ? detail::checkPcd(f, file_size, path, error)
                      : detail::checkPly(f, file_size, path, error);
  std::fclose(f);
  return ok;
}

/** Loads a .pcd or .ply into \a cloud and checks it is complete and has x, y, z.
 *  On failure returns false with a message in \a error. */
inline bool
loadCloud2(const std::string& path, pcl::PCLPointCloud2& cloud, std::string& error)
{
  struct stat st;
  if (stat(path.c_str(), &st) != 0) {
    error = "cannot open '" + path + "': " + std::strerror(errno);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    error = "'" + path + "' is not a regular file";
    return false;
  }
  if (st.st_size == 0) {
    error = "'" + path + "' is empty (0 bytes)";
    return false;
  }
  const std::string ext = extension(path);
  if ((ext == ".pcd" || ext == ".ply") &&
      !checkCloudFile(path, static_cast<long long>(st.st_size), error))
    return false;
  if (ext != ".pcd" && ext != ".ply") {
    error = "'" + path + "': unknown extension (use .pcd or .ply)";
    return false;
  }
  int rc = -1;
  /* PCL's readers throw on some headers the checks above let through (a
   * field name with bytes that split it in two: std::out_of_range). */
  try {
    if (ext == ".pcd") {
      pcl::PCDReader reader;
      rc = reader.read(path, cloud);
    }
    else {
      pcl::PLYReader reader;
      rc = reader.read(path, cloud);
    }
  }
  catch (const std::exception& e) {
    error = "cannot read '" + path + "': " + e.what();
    return false;
  }
  if (rc < 0) {
    error = "cannot read '" + path + "' (not a valid " + ext.substr(1) +
            " file, or truncated)";
    return false;
  }
  const std::size_t points = static_cast<std::size_t>(cloud.width) * cloud.height;
  if (cloud.data.size() != points * cloud.point_step) {
    error = "'" + path + "' is truncated or inconsistent: header says " +
            std::to_string(points) + " points, data holds " +
            std::to_string(cloud.point_step ? cloud.data.size() / cloud.point_step : 0);
    return false;
  }
  if (pcl::getFieldIndex(cloud, "x") < 0 || pcl::getFieldIndex(cloud, "y") < 0 ||
      pcl::getFieldIndex(cloud, "z") < 0) {
    error = "'" + path + "' has no x, y, z fields";
    return false;
  }
  return true;
}

/** True if the cloud has all of the named fields. */
inline bool
hasFields(const pcl::PCLPointCloud2& cloud, std::initializer_list<const char*> names)
{
  for (const char* n : names)
    if (pcl::getFieldIndex(cloud, n) < 0)
      return false;
  return true;
}

/** Value of a numeric field element as double. */
inline double
readValue(const std::uint8_t* p, std::uint8_t datatype)
{
  switch (datatype) {
  case pcl::PCLPointField::INT8: {
    std::int8_t v;
    std::memcpy(&v, p, 1);
    return v;
  }
  case pcl::PCLPointField::UINT8:
    return *p;
  case pcl::PCLPointField::INT16: {
    std::int16_t v;
    std::memcpy(&v, p, 2);
    return v;
  }
  case pcl::PCLPointField::UINT16: {
    std::uint16_t v;
    std::memcpy(&v, p, 2);
    return v;
  }
  case pcl::PCLPointField::INT32: {
    std::int32_t v;
    std::memcpy(&v, p, 4);
    return v;
  }
  case pcl::PCLPointField::UINT32: {
    std::uint32_t v;
    std::memcpy(&v, p, 4);
    return v;
  }
  case pcl::PCLPointField::FLOAT32: {
    float v;
    std::memcpy(&v, p, 4);
    return v;
  }
  case pcl::PCLPointField::FLOAT64: {
    double v;
    std::memcpy(&v, p, 8);
    return v;
  }
  default:
    return std::numeric_limits<double>::quiet_NaN();
  }
}

/** Reads three named fields of every point into packed values (3 per point),
 *  float by default; readTriplet<double> keeps double input exact. */
template <typename T = float>
inline std::vector<T>
readTriplet(const pcl::PCLPointCloud2& cloud,
            const char* a,
            const char* b,
            const char* c)
{
  const std::size_t n = static_cast<std::size_t>(cloud.width) * cloud.height;
  std::vector<T> out(3 * n);
  const char* names[3] = {a, b, c};
  for (int f = 0; f < 3; ++f) {
    const pcl::PCLPointField& field = cloud.fields[pcl::getFieldIndex(cloud, names[f])];
    for (std::size_t i = 0; i < n; ++i)
      out[3 * i + f] = static_cast<T>(
          readValue(&cloud.data[i * cloud.point_step + field.offset], field.datatype));
  }
  return out;
}

/** A local frame for float work: the centre of the finite points' bounding box
 *  and its largest side, used only when float is at risk: georeferenced scans
 *  (offsets of 1e5-1e7 m keep a 0.5 m grid in float) and clouds whose squared
 *  distances leave float's range (sides above 1e6 or below 1e-6). Other
 *  clouds keep the identity frame, so their results do not change with it
 *  (measured: re-centring ordinary clouds moved rounding enough to redraw two
 *  frames' seed lottery). */
struct LocalFrame {
  double centre[3] = {0.0, 0.0, 0.0};
  double scale = 1.0;
};

inline LocalFrame
localFrame(const std::vector<double>& xyz)
{
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL},
         hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) {
    if (!std::isfinite(xyz[i]) || !std::isfinite(xyz[i + 1]) ||
        !std::isfinite(xyz[i + 2]))
      continue;
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], xyz[i + d]);
      hi[d] = std::max(hi[d], xyz[i + d]);
    }
  }
  LocalFrame f;
  if (!(lo[0] <= hi[0]))
    return f;
  double side = 0.0, far = 0.0, centre[3];
  for (int d = 0; d < 3; ++d) {
    centre[d] = 0.5 * lo[d] + 0.5 * hi[d];
    side = std::max(side, hi[d] - lo[d]);
    far = std::max(far, std::fabs(centre[d]));
  }
  if (!(side > 0.0) || !std::isfinite(side))
    return f;
  if (far > 1e3 * side || side > 1e6 || side < 1e-6) {
    for (int d = 0; d < 3; ++d)
      f.centre[d] = centre[d];
    f.scale = side;
  }
  return f;
}

/** Copy of \a in without the named fields (data repacked). */
inline pcl::PCLPointCloud2
removeFields(const pcl::PCLPointCloud2& in, std::initializer_list<const char*> names)
{
  pcl::PCLPointCloud2 out;
  out.header = in.header;
  out.width = in.width;
  out.height = in.height;
  out.is_bigendian = in.is_bigendian;
  out.is_dense = in.is_dense;
  std::vector<const pcl::PCLPointField*> kept;
  std::uint32_t offset = 0;
  for (const auto& f : in.fields) {
    if (std::any_of(
            names.begin(), names.end(), [&](const char* n) { return f.name == n; }))
      continue;
    pcl::PCLPointField g = f;
    g.offset = offset;
    offset += static_cast<std::uint32_t>(pcl::getFieldSize(f.datatype)) *
              std::max<std::uint32_t>(f.count, 1);
    out.fields.push_back(g);
    kept.push_back(&f);
  }
  out.point_step = offset;
  out.row_step = out.point_step * out.width;
  const std::size_t n = static_cast<std::size_t>(in.width) * in.height;
  out.data.resize(n * out.point_step);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t f = 0; f < kept.size(); ++f) {
      const std::size_t bytes =
          static_cast<std::size_t>(pcl::getFieldSize(kept[f]->datatype)) *
          std::max<std::uint32_t>(kept[f]->count, 1);
      std::memcpy(&out.data[i * out.point_step + out.fields[f].offset],
                  &in.data[i * in.point_step + kept[f]->offset],
                  bytes);
    }
  return out;
}

/** Copy of \a in with 4-byte fields of one \a datatype (FLOAT32, INT32 or
 *  UINT32) appended after the existing ones; \a values holds names.size()
 *  4-byte values per point. */
inline pcl::PCLPointCloud2
appendFields4(const pcl::PCLPointCloud2& in,
              const std::vector<std::string>& names,
              std::uint8_t datatype,
              const void* values)
{
  pcl::PCLPointCloud2 out;
  out.header = in.header;
  out.width = in.width;
  out.height = in.height;
  out.is_bigendian = in.is_bigendian;
  out.is_dense = in.is_dense;
  out.fields = in.fields;
  const std::uint32_t extra = static_cast<std::uint32_t>(4 * names.size());
  for (std::size_t f = 0; f < names.size(); ++f) {
    pcl::PCLPointField g;
    g.name = names[f];
    g.offset = in.point_step + static_cast<std::uint32_t>(4 * f);
    g.datatype = datatype;
    g.count = 1;
    out.fields.push_back(g);
  }
  out.point_step = in.point_step + extra;
  out.row_step = out.point_step * out.width;
  const std::size_t n = static_cast<std::size_t>(in.width) * in.height;
  out.data.resize(n * out.point_step);
  const std::uint8_t* src = static_cast<const std::uint8_t*>(values);
  for (std::size_t i = 0; i < n; ++i) {
    if (in.point_step > 0)
      std::memcpy(
          &out.data[i * out.point_step], &in.data[i * in.point_step], in.point_step);
    std::memcpy(&out.data[i * out.point_step + in.point_step], src + i * extra, extra);
  }
  return out;
}

/** Copy of \a in with FLOAT32 fields appended after the existing ones;
 *  \a values holds names.size() floats per point. */
inline pcl::PCLPointCloud2
appendFloatFields(const pcl::PCLPointCloud2& in,
                  const std::vector<std::string>& names,
                  const std::vector<float>& values)
{
  return appendFields4(in, names, pcl::PCLPointField::FLOAT32, values.data());
}

/** Copy of \a in with INT32 fields appended after the existing ones;
 *  \a values holds names.size() integers per point. */
inline pcl::PCLPointCloud2
appendInt32Fields(const pcl::PCLPointCloud2& in,
                  const std::vector<std::string>& names,
                  const std::vector<std::int32_t>& values)
{
  return appendFields4(in, names, pcl::PCLPointField::INT32, values.data());
}

/** Reads one named numeric field of every point as int32 (rounded toward
 *  zero; NaN and out-of-range values become -1). The field must exist. */
inline std::vector<std::int32_t>
readInt32Field(const pcl::PCLPointCloud2& cloud, const char* name)
{
  const std::size_t n = static_cast<std::size_t>(cloud.width) * cloud.height;
  const pcl::PCLPointField& field = cloud.fields[pcl::getFieldIndex(cloud, name)];
  std::vector<std::int32_t> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double v =
        readValue(&cloud.data[i * cloud.point_step + field.offset], field.datatype);
    out[i] = std::isfinite(v) && v >= -2147483648.0 && v <= 2147483647.0
                 ? static_cast<std::int32_t>(v)
                 : -1;
  }
  return out;
}

/** Reads one named numeric field of every point as float. The field must exist. */
inline std::vector<float>
readFloatField(const pcl::PCLPointCloud2& cloud, const char* name)
{
  const std::size_t n = static_cast<std::size_t>(cloud.width) * cloud.height;
  const pcl::PCLPointField& field = cloud.fields[pcl::getFieldIndex(cloud, name)];
  std::vector<float> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = static_cast<float>(
        readValue(&cloud.data[i * cloud.point_step + field.offset], field.datatype));
  return out;
}

/** A coloured copy of packed points for pcl_viewer: x y z rgb, plus
 *  normal_x/y/z when \a normals is not empty; \a colour(i, rgb) paints point i. */
template <typename Colour>
inline pcl::PCLPointCloud2
colouredCloud(const std::vector<float>& xyz,
              const std::vector<float>& normals,
              Colour colour,
              bool is_dense)
{
  const std::size_t n = xyz.size() / 3;
  pcl::PointCloud<pcl::PointXYZRGBNormal> cloud;
  cloud.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    pcl::PointXYZRGBNormal& p = cloud[i];
    p.getVector3fMap() << xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2];
    if (!normals.empty())
      p.getNormalVector3fMap() << normals[3 * i], normals[3 * i + 1],
          normals[3 * i + 2];
    p.curvature = 0.0f;
    std::uint8_t rgb[3] = {0, 0, 0};
    colour(i, rgb);
    p.r = rgb[0];
    p.g = rgb[1];
    p.b = rgb[2];
  }
  cloud.is_dense = is_dense;
  pcl::PCLPointCloud2 out;
  if (normals.empty()) {
    pcl::PointCloud<pcl::PointXYZRGB> plain;
    pcl::copyPointCloud(cloud, plain);
    pcl::toPCLPointCloud2(plain, out);
  }
  else
    pcl::toPCLPointCloud2(cloud, out);
  return out;
}

/** x y z rgb normal_x normal_y normal_z of a cloud with normals, every point
 *  coloured by its normal, RGB = (n + 1) / 2: pcl_viewer draws -normals as
 *  undirected segments, the colour shows the sign (+z = blue, -z = olive; a
 *  region facing the wrong way shows in the complementary colour). Points
 *  without a finite normal are black. */
inline pcl::PCLPointCloud2
normalsColored(const pcl::PCLPointCloud2& in)
{
  const std::vector<float> nrm = readTriplet(in, "normal_x", "normal_y", "normal_z");
  pcl::PCLPointCloud2 out = colouredCloud(
      readTriplet(in, "x", "y", "z"),
      nrm,
      [&](std::size_t i, std::uint8_t rgb[3]) {
        const float* v = &nrm[3 * i];
        if (std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]))
          for (int d = 0; d < 3; ++d)
            rgb[d] = static_cast<std::uint8_t>(
                std::lround(127.5 * (1.0 + std::max(-1.0f, std::min(1.0f, v[d])))));
      },
      in.is_dense);
  out.width = in.width;
  out.height = in.height;
  return out;
}

/* ---- safe output -------------------------------------------------------
 * A tool never leaves a half-written file, nor destroys the one it replaces
 * (`pcl_dacpo_orient scan.ply scan.ply` on a full disk): every output goes to a
 * temporary file in the target's folder, is checked, synced to disk and only
 * then renamed over the target. PCL's writers do not report write errors (and
 * its PCD writer maps the file, which dies with SIGBUS on a full disk), so PCD
 * data is produced in memory and written here with every call checked, and
 * PLY files written by PCL are read back and their size checked. */

/** errno as text, with the path. */
inline std::string
ioError(const std::string& what, const std::string& path)
{
  return what + " '" + path + "': " + std::strerror(errno);
}

/** Writes \a bytes to \a path (created or truncated), checking every write,
 *  fsync and close; messages name \a shown (the file the user asked for). */
inline bool
writeAllChecked(const std::string& path,
                const std::string& bytes,
                std::string& error,
                const std::string& shown = std::string())
{
  const std::string& name = shown.empty() ? path : shown;
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    error = ioError("cannot create", name);
    return false;
  }
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t w = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (w < 0 && errno == EINTR)
      continue;
    if (w <= 0) {
      error = ioError("cannot write", name);
      ::close(fd);
      return false;
    }
    done += static_cast<std::size_t>(w);
  }
  if (::fsync(fd) != 0) {
    error = ioError("cannot sync", name);
    ::close(fd);
    return false;
  }
  if (::close(fd) != 0) {
    error = ioError("cannot close", name);
    return false;
  }
  return true;
}

/** fsync of a file written by someone else (PCL). */
inline bool
syncFile(const std::string& path, std::string& error)
{
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    error = ioError("cannot reopen", path);
    return false;
  }
  const bool ok = ::fsync(fd) == 0;
  if (!ok)
    error = ioError("cannot sync", path);
  ::close(fd);
  return ok;
}

namespace detail {
/** Bytes of a PLY scalar type, 0 for an unknown name. */
inline unsigned
plyTypeBytes(const std::string& type)
{
  static const char* const names[][2] = {
      {"char", "1"},   {"uchar", "1"},  {"int8", "1"},    {"uint8", "1"},   {"short", "2"},
      {"ushort", "2"}, {"int16", "2"},  {"uint16", "2"},  {"int", "4"},     {"uint", "4"},
      {"float", "4"},  {"int32", "4"},  {"uint32", "4"},  {"float32", "4"}, {"double", "8"},
      {"float64", "8"}};
  for (const auto& n : names)
    if (type == n[0])
      return static_cast<unsigned>(n[1][0] - '0');
  return 0;
}

/** One element of a PLY header: its row count and, per property, the bytes of
 *  a scalar, or of a list's count and items. */
struct PlyElementLayout {
  unsigned long long count = 0;
  std::vector<std::pair<unsigned, unsigned>> props; /* (count bytes or 0, item bytes) */
};

/** Bytes of the rows of e starting at the current offset of f: count x record
 *  for scalar rows; list rows (PCL's range_grid of organized clouds) are walked
 *  count by count. -1 when the data ends first or a count is malformed. */
inline long long
plyElementBytes(std::FILE* f, const PlyElementLayout& e)
{
  unsigned long long record = 0;
  bool lists = false;
  for (const auto& p : e.props) {
    record += p.first ? 0 : p.second;
    lists = lists || p.first != 0;
  }
  if (!lists)
    return static_cast<long long>(e.count * record);
  long long bytes = 0;
  for (unsigned long long r = 0; r < e.count; ++r)
    for (const auto& p : e.props) {
      unsigned long long n = 1;
      if (p.first) {
        unsigned char c[4] = {0, 0, 0, 0};
        if (p.first > 4 || std::fread(c, 1, p.first, f) != p.first)
          return -1;
        n = c[0] | (c[1] << 8) | (static_cast<unsigned long long>(c[2]) << 16) |
            (static_cast<unsigned long long>(c[3]) << 24);
        bytes += p.first;
      }
      if (::fseeko(f, static_cast<off_t>(n * p.second), SEEK_CUR) != 0)
        return -1;
      bytes += static_cast<long long>(n * p.second);
    }
  return bytes;
}
} // namespace detail

/** Size a binary little-endian PLY must have: its header plus the bytes of
 *  every element's rows (list rows walked one by one). 0 if that cannot be
 *  told (not binary little-endian, an unknown type, data that ends early). */
inline long long
expectedBinaryPlySize(const std::string& path)
{
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f)
    return 0;
  std::string line;
  std::vector<detail::PlyElementLayout> elements;
  bool binary = false, ok = true;
  while (ok && detail::readLine(f, line, 4096)) {
    const std::vector<std::string> t = detail::tokens(line);
    if (t.empty())
      continue;
    if (t[0] == "format")
      binary = t.size() >= 2 && t[1] == "binary_little_endian";
    else if (t[0] == "element" && t.size() == 3) {
      elements.emplace_back();
      elements.back().count = std::strtoull(t[2].c_str(), nullptr, 10);
    }
    else if (t[0] == "property" && !elements.empty()) {
      const bool list = t.size() == 5 && t[1] == "list";
      const unsigned c = list ? detail::plyTypeBytes(t[2]) : 0;
      const unsigned v = detail::plyTypeBytes(t[list ? 3 : 1]);
      ok = v != 0 && (list ? c != 0 : t.size() == 3);
      elements.back().props.emplace_back(c, v);
    }
    else if (t[0] == "end_header")
      break;
  }
  long long total = std::ftell(f);
  for (std::size_t i = 0; ok && binary && i < elements.size(); ++i) {
    const long long b = detail::plyElementBytes(f, elements[i]);
    ok = b >= 0;
    total += b;
    /* a scalar element was not read past: move over it for the next one */
    if (ok && i + 1 < elements.size())
      ok = ::fseeko(f, static_cast<off_t>(total), SEEK_SET) == 0;
  }
  std::fclose(f);
  return binary && ok ? total : 0;
}

/** Produces \a path through a temporary file beside it: \a produce writes the
 *  temporary file (given its name), then it is synced and renamed over \a path.
 *  On any failure the temporary file is removed and \a path is untouched. */
template <typename Produce>
bool
writeAtomically(const std::string& path, Produce produce, std::string& error)
{
  char name[4352];
  if (dacpo_temp_sibling(path.c_str(), "tmp", static_cast<long>(::getpid()), name,
                         sizeof(name)) != 0) {
    error = "'" + path + "': name too long for a temporary file beside it";
    return false;
  }
  const std::string tmp = name;
  /* a SIGINT or SIGTERM while it is written removes it (dacpo_cleanup.h) */
  const int slot = dacpo_cleanup_add(tmp.c_str());
  const bool ok = produce(tmp, error) && syncFile(tmp, error);
  if (ok && std::rename(tmp.c_str(), path.c_str()) == 0) {
    dacpo_cleanup_drop(slot);
    return true;
  }
  if (ok)
    error = ioError("cannot replace", path);
  std::remove(tmp.c_str());
  dacpo_cleanup_drop(slot);
  return false;
}

/** Writes binary-compressed PCD or binary PLY by extension, safely (above). */
inline bool
saveCloud2(const std::string& path,
           const pcl::PCLPointCloud2& cloud,
           std::string& error)
{
  const std::string ext = extension(path);
  if (ext != ".pcd" && ext != ".ply") {
    error = "'" + path + "': unknown extension (use .pcd or .ply)";
    return false;
  }
  return writeAtomically(
      path,
      [&](const std::string& tmp, std::string& err) {
        if (ext == ".pcd") {
          std::ostringstream os;
          pcl::PCDWriter writer;
          if (writer.writeBinaryCompressed(os, cloud) < 0 || !os) {
            err = "cannot encode '" + path + "' as PCD";
            return false;
          }
          return writeAllChecked(tmp, os.str(), err, path);
        }
        pcl::PLYWriter writer;
        const int rc = writer.writeBinary(
            tmp, cloud, Eigen::Vector4f::Zero(), Eigen::Quaternionf::Identity(), false);
        struct stat st;
        const long long want = expectedBinaryPlySize(tmp);
        if (rc < 0 || ::stat(tmp.c_str(), &st) != 0 || want == 0 ||
            st.st_size != want) {
          err =
              "cannot write '" + path + "' (short write: disk full or no permission?)";
          return false;
        }
        return true;
      },
      error);
}

/** Strict parse of a non-negative integer (no sign, no trailing junk). */
inline bool
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

/** Strict parse of a finite number. */
inline bool
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
