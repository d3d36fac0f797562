/* SPDX-License-Identifier: BSD-3-Clause */
/* Shared by the pcl_dacpo_* tools: a PCD or PLY file's own structure checked
 * before PCL parses it (PCL's readers crash or read past the end on some
 * malformed files), and the size a binary PLY must have. Header-only, tools
 * only (not installed). */
#pragma once

#include "dacpo_tool_options.h"

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace dacpo_tool {

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

} // namespace dacpo_tool
