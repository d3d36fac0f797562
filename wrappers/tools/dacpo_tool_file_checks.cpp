/* SPDX-License-Identifier: BSD-3-Clause */
/* The pcl_dacpo_* tools' checks of a PCD or PLY file before PCL reads it
 * (dacpo_tool_file_checks.h): the support library parses the header, the
 * checks here hold it to what PCL's readers need and go through the data. */
#include "dacpo_tool_file_checks.h"

#include "dacpo_pcd.h"
#include "dacpo_ply.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace dacpo_tool {

namespace detail {
namespace {

/** A whole token that strtod takes (numbers, nan, inf). */
bool
isNumber(const std::string& t)
{
  if (t.empty())
    return false;
  char* end = nullptr;
  errno = 0;
  (void)std::strtod(t.c_str(), &end);
  return end == t.c_str() + t.size();
}

std::vector<std::string>
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
std::string
printable(std::string s)
{
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126)
      c = '?';
  return s;
}

/** Reads one '\n'-terminated line (without it); false at end of file. */
bool
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

bool
parseCount(const std::string& t, unsigned long long& v)
{
  if (t.empty() || t.find_first_not_of("0123456789") != std::string::npos ||
      t.size() > 19)
    return false;
  v = std::strtoull(t.c_str(), nullptr, 10);
  return true;
}

/** Where a file check stands, and its error message: "'path' is not a valid
 *  KIND file: line N: what" (the support library's header messages read the
 *  same). */
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

/** A message buffer for the support library's errors about \a path. */
std::vector<char>
messageBuffer(const std::string& path)
{
  return std::vector<char>(path.size() + 1024, '\0');
}

/** What PCL's reader needs of a parsed PCD header beyond its syntax: COUNT at
 *  most 100000, WIDTH and POINTS, WIDTH x HEIGHT = POINTS; bytes and values
 *  per point. */
bool
checkPcdLayout(FileCheck& fc,
               const dacpo_pcd_header& h,
               unsigned long long& point_size,
               unsigned long long& values)
{
  point_size = h.record;
  values = 0;
  for (int i = 0; i < h.nf; ++i) {
    if (h.f[i].count > 100000)
      return fc.bad("COUNT of field '" + std::string(h.f[i].name) +
                    "' is more than 100000");
    values += h.f[i].count;
  }
  if (!h.have_width || !h.have_points)
    return fc.bad("WIDTH and POINTS are required");
  const unsigned long long width = h.width, points = h.points;
  const unsigned long long height = h.have_height ? h.height : 1;
  if (width > (1ull << 40) || height > (1ull << 40) || width * height != points)
    return fc.bad("WIDTH x HEIGHT differs from POINTS");
  return true;
}

/** binary_compressed: the two sizes in front of the data against the header and
 *  the file. */
bool
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
bool
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

/** binary: PCL 1.13 throws an uncaught std::length_error (abort) when the data
 *  starts with the bytes of the old header keyword COLUMNS (found by fuzzing);
 *  then the data must hold every point. */
bool
checkPcdBinary(std::FILE* f,
               FileCheck& fc,
               const dacpo_pcd_header& h,
               long long data_bytes,
               unsigned long long point_size)
{
  const long long header_end = std::ftell(f);
  char head[7] = {0};
  const std::size_t got = std::fread(head, 1, sizeof(head), f);
  if (got == sizeof(head) && std::memcmp(head, "COLUMNS", sizeof(head)) == 0)
    return fc.bad(
        "the binary data starts with 'COLUMNS', which PCL's reader takes for a "
        "header line");
  std::fseek(f, header_end, SEEK_SET);
  const unsigned long long points = h.points;
  if (std::strcmp(h.data, "binary") == 0 && points > 0 &&
      (unsigned long long)data_bytes < points * point_size)
    return fc.bad("binary data is truncated: " + std::to_string(points) +
                  " points of " + std::to_string(point_size) + " bytes need " +
                  std::to_string(points * point_size) + " bytes, the file holds " +
                  std::to_string(data_bytes));
  return true;
}

/** The PCD header (the support library's parser), its layout, then the data
 *  of its DATA kind. */
bool
checkPcd(std::FILE* f, long long file_size, const std::string& path, std::string& error)
{
  FileCheck fc{path, "PCD", error};
  dacpo_pcd_header h;
  std::vector<char> msg = messageBuffer(path);
  if (dacpo_pcd_read_header(f, path.c_str(), &h, msg.data(), msg.size()) !=
      DACPO_PLY_OK) {
    error = msg.data();
    return false;
  }
  fc.lineno = static_cast<std::size_t>(h.lines);
  unsigned long long point_size = 0, values = 0;
  if (!checkPcdLayout(fc, h, point_size, values))
    return false;
  const long long data_bytes = file_size - std::ftell(f);
  if (std::strcmp(h.data, "ascii") == 0)
    return checkPcdAscii(f, fc, data_bytes, h.points, values);
  if (!checkPcdBinary(f, fc, h, data_bytes, point_size))
    return false;
  return std::strcmp(h.data, "binary_compressed") != 0 ||
         checkPcdCompressed(f, fc, data_bytes, h.points, point_size);
}

/** Every record takes at least this many bytes: binary, its scalars (a list at
 *  least its length); ASCII, one character and a separator per value. The
 *  data_bytes after the header must hold them all, and no element may claim
 *  more records than there are data bytes (PCL walks the records of an
 *  element without properties one by one: a count of 2^64 hung it). */
bool
checkPlyCounts(FileCheck& fc, const dacpo_ply_header_info& info, long long data_bytes)
{
  unsigned long long need = 0;
  for (int i = 0; i < info.nelements; ++i) {
    const dacpo_ply_element_info& e = info.elements[i];
    unsigned long long min_bytes = 0;
    for (int j = 0; j < e.nprops; ++j)
      min_bytes += e.props[j].count_bytes ? e.props[j].count_bytes : e.props[j].bytes;
    const unsigned long long per =
        info.format == DACPO_PLY_ASCII ? 2 * std::max(1, e.nprops) : min_bytes;
    if (e.count > static_cast<unsigned long long>(std::max(0LL, data_bytes)) /
                      std::max(per, 1ull))
      return fc.bad("the header claims " + std::to_string(e.count) +
                    " records, more than the file's " + std::to_string(data_bytes) +
                    " data bytes can hold");
    need += e.count * per;
  }
  if (need > static_cast<unsigned long long>(std::max(0LL, data_bytes)))
    return fc.bad("the data is shorter than the header says");
  return true;
}

/** One ASCII record of an element with the properties \a e: exactly its
 *  values (list lengths included), all numbers. */
bool
checkPlyRecord(FileCheck& fc, const dacpo_ply_element_info& e, const std::string& line)
{
  const std::vector<std::string> t = tokens(line);
  std::size_t k = 0;
  for (int j = 0; j < e.nprops; ++j) {
    unsigned long long n = 1;
    if (e.props[j].count_bytes != 0) {
      if (k >= t.size() || !parseCount(t[k], n))
        return fc.bad("a list length is missing or not a count");
      ++k;
    }
    for (unsigned long long v = 0; v < n; ++v, ++k) {
      if (k >= t.size())
        return fc.bad("too few values");
      if (!isNumber(t[k]))
        return fc.bad("'" + t[k].substr(0, 40) + "' is not a number");
    }
  }
  if (k != t.size())
    return fc.bad("too many values");
  return true;
}

/** ASCII data: every record of every element holds exactly its values (list
 *  lengths included), all numbers. */
bool
checkPlyAscii(std::FILE* f, FileCheck& fc, const dacpo_ply_header_info& info)
{
  std::string line;
  for (int i = 0; i < info.nelements; ++i)
    for (unsigned long long r = 0; r < info.elements[i].count; ++r) {
      if (!readLine(f, line))
        return fc.bad("the data ends early");
      ++fc.lineno;
      if (!checkPlyRecord(fc, info.elements[i], line))
        return false;
    }
  return true;
}

/** The PLY header (the support library's parser), element counts the file
 *  can hold, and for ASCII PLY every value of every element line a number. */
bool
checkPly(std::FILE* f, long long file_size, const std::string& path, std::string& error)
{
  FileCheck fc{path, "PLY", error};
  const std::unique_ptr<dacpo_ply_header_info> info(new dacpo_ply_header_info);
  std::vector<char> msg = messageBuffer(path);
  if (dacpo_ply_read_header(f, path.c_str(), info.get(), msg.data(), msg.size()) !=
      DACPO_PLY_OK) {
    error = msg.data();
    return false;
  }
  fc.lineno = static_cast<std::size_t>(info->lines);
  if (!checkPlyCounts(fc, *info, file_size - std::ftell(f)))
    return false;
  return info->format != DACPO_PLY_ASCII || checkPlyAscii(f, fc, *info);
}

} // namespace
} // namespace detail

bool
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

long long
expectedBinaryPlySize(const std::string& path)
{
  unsigned long long bytes = 0;
  std::vector<char> msg = detail::messageBuffer(path);
  if (dacpo_ply_binary_size(path.c_str(), &bytes, msg.data(), msg.size()) !=
      DACPO_PLY_OK)
    return 0;
  return static_cast<long long>(bytes);
}

} // namespace dacpo_tool
