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
#include <cmath>
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

/** The words of \a s between any of \a delims (none empty; pcl::split). */
std::vector<std::string>
splitAt(const std::string& s, const char* delims)
{
  std::vector<std::string> out;
  for (std::size_t i = s.find_first_not_of(delims); i != std::string::npos;) {
    const std::size_t j = s.find_first_of(delims, i);
    out.push_back(s.substr(i, j == std::string::npos ? j : j - i));
    i = j == std::string::npos ? j : s.find_first_not_of(delims, j);
  }
  return out;
}

/** Whether \a word starts with \a key. */
bool
startsWith(const std::string& word, const char* key)
{
  return word.compare(0, std::strlen(key), key) == 0;
}

/** PCL 1.13's PCD header reader does not stop at DATA: it reads the data's
 *  lines as header lines until one whose first word (std::istream >>) starts
 *  with no keyword. Empty lines, comments, VERSION and VIEWPOINT pass; a DATA
 *  line moves the data behind it (\a start) and may set its \a kind (by the
 *  prefix of its second word; none: PCL throws, a clean failure), which the
 *  checks then follow; FIELDS, COLUMNS, SIZE, TYPE, COUNT, WIDTH, HEIGHT or
 *  POINTS change the layout and are refused (found by fuzzing: data starting
 *  with 'COLUMNS' threw std::length_error, 'DATA binary\nCOLUMNS' was a
 *  segfault). \a f is at the binary data. */
bool
checkPcdDataLines(std::FILE* f, FileCheck& fc, std::string& kind, long long& start)
{
  static const char* const layout[] = {
      "FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "POINTS"};
  const std::size_t header_lines = fc.lineno;
  start = std::ftell(f);
  std::string line;
  for (std::size_t k = 1; readLine(f, line); ++k) {
    const std::vector<std::string> w = splitAt(line, " \t\v\f\r");
    const std::string word = w.empty() ? std::string() : w[0];
    if (line.empty() || startsWith(word, "#") || startsWith(word, "VERSION") ||
        startsWith(word, "VIEWPOINT"))
      continue;
    fc.lineno = header_lines + k;
    if (startsWith(word, "DATA")) {
      const std::vector<std::string> st = splitAt(line, "\t\r ");
      if (st.size() < 2)
        break; /* PCL's reader throws std::out_of_range: it fails cleanly */
      kind = startsWith(st[1], "binary_compressed") ? "binary_compressed"
             : startsWith(st[1], "binary")          ? "binary"
                                                    : kind;
      start = std::ftell(f);
      continue;
    }
    for (const char* key : layout)
      if (startsWith(word, key))
        return fc.bad(std::string("the binary data ") +
                      (k == 1 ? "starts" : "has a line starting") + " with '" + key +
                      "', which PCL's reader takes for a header line");
    break;
  }
  fc.lineno = header_lines;
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
  if (std::strcmp(h.data, "ascii") == 0)
    return checkPcdAscii(f, fc, file_size - std::ftell(f), h.points, values);
  std::string kind = h.data; /* and where PCL's reader takes the data to start */
  long long start = 0;
  if (!checkPcdDataLines(f, fc, kind, start))
    return false;
  std::fseek(f, start, SEEK_SET);
  const long long data_bytes = file_size - start;
  if (kind == "binary" && h.points > 0 &&
      (unsigned long long)data_bytes < h.points * point_size)
    return fc.bad("binary data is truncated: " + std::to_string(h.points) +
                  " points of " + std::to_string(point_size) + " bytes need " +
                  std::to_string(h.points * point_size) + " bytes, the file holds " +
                  std::to_string(data_bytes));
  return kind != "binary_compressed" ||
         checkPcdCompressed(f, fc, data_bytes, h.points, point_size);
}

/** A header line split at spaces and tabs as PCL's PLY reader splits an
 *  obj_info line (boost::split, runs compressed): a blank in front or at the
 *  end gives an empty first or last word. */
std::vector<std::string>
blankSplit(const std::string& line)
{
  std::vector<std::string> out(1);
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (line[i] != ' ' && line[i] != '\t')
      out.back().push_back(line[i]);
    else if (i == 0 || (line[i - 1] != ' ' && line[i - 1] != '\t'))
      out.emplace_back();
  }
  return out;
}

/** What PCL 1.13's PLY reader needs of the lists in the rows of an element:
 *  a range_grid row's first index a vertex (when it maps them), a vertex
 *  list no longer than in the first row (it sizes the field by that row). */
struct PclListRule {
  int grid = -1;         /* range_grid: the list of vertex indices, or -1 */
  std::string grid_item; /* the type of its items */
  std::vector<std::pair<int, std::string>> fixed; /* vertex: lists, names */
};

/** What PCL 1.13's PLY reader makes of a header beyond its syntax: the
 *  cloud's width and height (obj_info num_cols and num_rows through atoi, as
 *  it holds them in 32 bits; else the vertex count by 1), the uchar colours
 *  of the vertex element, which it packs into one rgb field, and the lists
 *  it reads (PclListRule, per element). */
struct PclPlyView {
  std::uint32_t width = 0, height = 0;
  std::size_t size_line = 0; /* the line that set them last */
  bool vertex = false;       /* a vertex element is declared */
  unsigned long long vertex_count = 0;
  unsigned long long grid_count = 0; /* rows of the range_grid elements */
  int element = -1;                  /* the element of the line read */
  int prop = -1;                     /* the property of the line read */
  bool in_vertex = false;            /* element is a vertex element */
  bool in_grid = false;              /* element is a range_grid element */
  int colour = 0; /* the vertex's uchar colours so far: 1 red, 2 red green */
  std::vector<PclListRule> lists; /* per element */

  /** PCL's reader builds the cloud from the range_grid rows (each one the
   *  vertex of its first index, or NaN) when their number is not the
   *  vertex count. */
  bool
  remaps() const
  {
    return grid_count > 0 && grid_count != vertex_count;
  }
};

/** An obj_info line: PCL asserts that its first word is obj_info (a blank in
 *  front aborted it); num_cols and num_rows set the cloud's size. */
bool
pclObjInfo(FileCheck& fc, PclPlyView& v, const std::string& line)
{
  const std::vector<std::string> w = blankSplit(line);
  if (w[0].empty())
    return fc.bad("the obj_info line starts with a blank, which PCL's reader "
                  "aborts on");
  if (w.size() < 3 || (w[1] != "num_cols" && w[1] != "num_rows"))
    return true;
  const auto n = static_cast<std::uint32_t>(std::strtol(w[2].c_str(), nullptr, 10));
  (w[1] == "num_cols" ? v.width : v.height) = n;
  v.size_line = fc.lineno;
  return true;
}

/** An element line: a vertex element sizes the cloud by its count unless
 *  num_cols and num_rows already did (both not 0). */
void
pclElement(const FileCheck& fc, PclPlyView& v, const std::vector<std::string>& w)
{
  v.in_vertex = w.size() == 3 && w[1] == "vertex";
  v.in_grid = w.size() == 3 && w[1] == "range_grid";
  v.colour = 0;
  ++v.element;
  v.prop = -1;
  if (v.in_grid)
    v.grid_count += std::strtoull(w[2].c_str(), nullptr, 10);
  if (!v.in_vertex)
    return;
  v.vertex = true;
  v.vertex_count = std::strtoull(w[2].c_str(), nullptr, 10);
  if (v.width == 0 || v.height == 0) {
    v.width = static_cast<std::uint32_t>(v.vertex_count);
    v.height = 1;
    v.size_line = fc.lineno;
  }
}

/** A property of the vertex element: PCL packs uchar red, green and blue (or
 *  diffuse_*) into one rgb field and misplaces the values unless they come
 *  in a row, in this order (green and blue without red wrote past the
 *  cloud's data and aborted it). */
bool
pclVertexProperty(FileCheck& fc, PclPlyView& v, const std::vector<std::string>& w)
{
  int step = 0; /* 1 red, 2 green, 3 blue */
  if (w.size() == 3 && (w[1] == "uchar" || w[1] == "uint8")) {
    const std::string n = w[2].compare(0, 8, "diffuse_") == 0 ? w[2].substr(8) : w[2];
    step = n == "red" ? 1 : n == "green" ? 2 : n == "blue" ? 3 : 0;
  }
  if (step == 0 ? v.colour != 0 : step != v.colour + 1)
    return fc.bad("vertex property '" + w.back().substr(0, 40) +
                  "' breaks the uchar colours: PCL's reader needs red, green and "
                  "blue in a row, in this order");
  v.colour = step % 3;
  return true;
}

/** Whether PCL's reader stores a list of these length and item types (it
 *  has callbacks for uchar lengths of int or uint, and int or uint lengths
 *  of any type; it skips other lists). */
bool
pclReadsList(const std::string& length, const std::string& item)
{
  if (length == "uchar" || length == "uint8")
    return item == "int" || item == "int32" || item == "uint" || item == "uint32";
  return length == "uint" || length == "uint32" || length == "int" || length == "int32";
}

/** A property line: the lists PCL reads (the vertex indices of a range_grid
 *  element, vertex_indices or vertex_index; the lists of a vertex element),
 *  the colours of a vertex element. */
bool
pclProperty(FileCheck& fc, PclPlyView& v, const std::vector<std::string>& w)
{
  ++v.prop;
  const auto e = static_cast<std::size_t>(v.element);
  if (e < v.lists.size() && w.size() == 5 && w[1] == "list" &&
      pclReadsList(w[2], w[3])) {
    PclListRule& rule = v.lists[e];
    if (v.in_vertex)
      rule.fixed.emplace_back(v.prop, w[4]);
    if (v.in_grid && (w[4] == "vertex_indices" || w[4] == "vertex_index") &&
        rule.grid < 0) {
      rule.grid = v.prop;
      rule.grid_item = w[3];
    }
  }
  return !v.in_vertex || pclVertexProperty(fc, v, w);
}

/** The cloud's size as PCL's reader takes it (num_cols x num_rows) against
 *  the vertex count: fewer made it write past the cloud's data (an
 *  assertion, SIGABRT), more is read as zero points (a huge size threw
 *  std::bad_alloc) unless a range_grid element of that many rows maps the
 *  vertices onto the grid (PCL's organized clouds without their NaN points). */
bool
checkPclCloudSize(FileCheck& fc, const PclPlyView& v)
{
  const unsigned long long points = static_cast<unsigned long long>(v.width) * v.height;
  if (points == v.vertex_count || (points > v.vertex_count && points == v.grid_count))
    return true;
  fc.lineno = v.size_line;
  return fc.bad("obj_info num_cols and num_rows make PCL's reader size the cloud " +
                std::to_string(v.width) + " x " + std::to_string(v.height) + " = " +
                std::to_string(points) + " points, but element vertex has " +
                std::to_string(v.vertex_count) +
                (points > v.vertex_count ? " and no range_grid maps them" : ""));
}

/** The header once more, as PCL's PLY reader takes it (PclPlyView, with the
 *  lists it reads): no obj_info line with a blank in front, uchar colours in
 *  a row, and a cloud size that is the vertex count (a smaller num_cols x
 *  num_rows made PCL write past the cloud's data and abort, a huge one
 *  throw bad_alloc) or that of the range_grid. */
bool
checkPlyForPcl(std::FILE* f,
               FileCheck& fc,
               const dacpo_ply_header_info& info,
               PclPlyView& v)
{
  v.lists.assign(static_cast<std::size_t>(info.nelements), PclListRule());
  std::string line;
  bool ok = std::fseek(f, 0, SEEK_SET) == 0 || fc.bad("cannot seek");
  for (fc.lineno = 1; ok && fc.lineno <= static_cast<std::size_t>(info.lines) &&
                      readLine(f, line);
       ++fc.lineno) {
    if (!line.empty() && line.back() == '\r')
      line.pop_back();
    const std::vector<std::string> w = tokens(line);
    if (fc.lineno == 1 || w.empty())
      continue;
    if ((w[0] == "element" || w[0] == "end_header") && v.in_vertex && v.colour != 0)
      ok = fc.bad("the uchar colours end before blue: PCL's reader needs red, "
                  "green and blue in a row, in this order");
    else if (w[0] == "obj_info")
      ok = pclObjInfo(fc, v, line);
    else if (w[0] == "element")
      pclElement(fc, v, w);
    else if (w[0] == "property")
      ok = pclProperty(fc, v, w);
  }
  if (ok && v.vertex)
    ok = checkPclCloudSize(fc, v);
  fc.lineno = static_cast<std::size_t>(info.lines);
  return ok && (std::fseek(f, static_cast<long>(info.data_offset), SEEK_SET) == 0 ||
                fc.bad("cannot seek"));
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

/** The lists of one element's rows as PCL's reader takes them
 *  (PclListRule): a mapped range_grid row's first index a vertex (PCL reads
 *  it as int32 and multiplies it by the point size in 32 bits: -1 read
 *  before the cloud's data, a segfault), a vertex list no longer than in
 *  the first row (a longer one wrote past the cloud's data, an assertion). */
struct PclListCheck {
  FileCheck& fc;
  const PclPlyView& v;
  const PclListRule& rule;
  std::vector<unsigned long long> first; /* per fixed list: its first length */

  PclListCheck(FileCheck& c, const PclPlyView& view, int element)
      : fc(c), v(view), rule(view.lists[static_cast<std::size_t>(element)]),
        first(rule.fixed.size(), 0)
  {
  }

  /** Whether the rows need a look (else they can be skipped). */
  bool
  active() const
  {
    return !rule.fixed.empty() || (rule.grid >= 0 && v.remaps());
  }

  /** Whether list \a j's first item matters. */
  bool
  wantsItem(int j) const
  {
    return j == rule.grid && v.remaps();
  }

  /** List \a j of row \a r: \a n items, the first \a item (when wanted). */
  bool
  list(unsigned long long r, int j, unsigned long long n, double item)
  {
    const double t = std::trunc(item);
    if (wantsItem(j) && n > 0 && !(t >= 0 && t < static_cast<double>(v.vertex_count))) {
      char text[64];
      std::snprintf(text, sizeof(text), "%.15g", item);
      return fc.bad("range_grid row " + std::to_string(r) + " maps to vertex " + text +
                    ", but element vertex has " + std::to_string(v.vertex_count) +
                    " (PCL's reader would read outside its data)");
    }
    for (std::size_t q = 0; q < rule.fixed.size(); ++q)
      if (rule.fixed[q].first == j && r == 0)
        first[q] = n;
      else if (rule.fixed[q].first == j && n > first[q])
        return fc.bad("vertex " + std::to_string(r) + " has " + std::to_string(n) +
                      " values in list '" + rule.fixed[q].second.substr(0, 40) +
                      "', more than the " + std::to_string(first[q]) +
                      " of vertex 0 (PCL's reader sizes the list by vertex 0)");
    return true;
  }
};

/** One ASCII record of an element with the properties \a e: exactly its
 *  values (list lengths included), all numbers; its lists as PCL's reader
 *  takes them (\a pcl, row \a r). */
bool
checkPlyRecord(FileCheck& fc,
               const dacpo_ply_element_info& e,
               const std::string& line,
               PclListCheck& pcl,
               unsigned long long r)
{
  const std::vector<std::string> t = tokens(line);
  std::size_t k = 0;
  for (int j = 0; j < e.nprops; ++j) {
    unsigned long long n = 1;
    const bool list = e.props[j].count_bytes != 0;
    if (list) {
      if (k >= t.size() || !parseCount(t[k], n))
        return fc.bad("a list length is missing or not a count");
      ++k;
    }
    const std::size_t items = k;
    for (unsigned long long v = 0; v < n; ++v, ++k) {
      if (k >= t.size())
        return fc.bad("too few values");
      if (!isNumber(t[k]))
        return fc.bad("'" + t[k].substr(0, 40) + "' is not a number");
    }
    if (list &&
        !pcl.list(r, j, n, n > 0 ? std::strtod(t[items].c_str(), nullptr) : 0.0))
      return false;
  }
  if (k != t.size())
    return fc.bad("too many values");
  return true;
}

/** ASCII data: every record of every element holds exactly its values (list
 *  lengths included), all numbers; lists as PCL's reader takes them. */
bool
checkPlyAscii(std::FILE* f,
              FileCheck& fc,
              const dacpo_ply_header_info& info,
              const PclPlyView& v)
{
  std::string line;
  for (int i = 0; i < info.nelements; ++i) {
    PclListCheck pcl(fc, v, i);
    for (unsigned long long r = 0; r < info.elements[i].count; ++r) {
      if (!readLine(f, line))
        return fc.bad("the data ends early");
      ++fc.lineno;
      if (!checkPlyRecord(fc, info.elements[i], line, pcl, r))
        return false;
    }
  }
  return true;
}

/** One binary row of \a e (\a f at it): its lists to \a pcl, row \a r. False
 *  with the message when PCL's reader would fail on them; \a end: the data
 *  ends early (left to the reader, which fails cleanly). */
bool
checkPlyRowBinary(std::FILE* f,
                  const dacpo_ply_element_info& e,
                  bool big,
                  PclListCheck& pcl,
                  unsigned long long r,
                  bool& end)
{
  static const char* const lengths[] = {"", "uint8", "uint16", "", "uint32"};
  unsigned char b[8];
  for (int j = 0; j < e.nprops && !end; ++j) {
    const dacpo_ply_property_info& p = e.props[j];
    const unsigned cb = p.count_bytes <= 4 ? p.count_bytes : 4;
    unsigned long long n = 1;
    double item = 0;
    end = cb != 0 && std::fread(b, 1, cb, f) != cb;
    if (cb != 0 && !end)
      n = static_cast<unsigned long long>(dacpo_ply_decode_named(b, lengths[cb], big));
    const bool first = cb != 0 && n > 0 && pcl.wantsItem(j) && !end;
    end = end || (first && std::fread(b, 1, p.bytes, f) != p.bytes);
    if (first && !end)
      item = dacpo_ply_decode_named(b, pcl.rule.grid_item.c_str(), big);
    if (!end && cb != 0 && !pcl.list(r, j, n, item))
      return false;
    const unsigned long long skip = (first ? n - 1 : n) * p.bytes;
    end = end || std::fseek(f, static_cast<long>(skip), SEEK_CUR) != 0;
  }
  return true;
}

/** Binary data: the rows of the elements with lists PCL's reader takes
 *  (PclListCheck) walked list by list; other elements skipped when their
 *  rows have one size, walked when not. */
bool
checkPlyListsBinary(std::FILE* f,
                    FileCheck& fc,
                    const dacpo_ply_header_info& info,
                    const PclPlyView& v)
{
  int last = -1;
  for (int i = 0; i < info.nelements; ++i)
    if (PclListCheck(fc, v, i).active())
      last = i;
  bool end = false;
  for (int i = 0; i <= last && !end; ++i) {
    const dacpo_ply_element_info& e = info.elements[i];
    PclListCheck pcl(fc, v, i);
    unsigned long long record = 0;
    for (int j = 0; j < e.nprops && record != ~0ull; ++j)
      record = e.props[j].count_bytes != 0 ? ~0ull : record + e.props[j].bytes;
    if (!pcl.active() && record != ~0ull) {
      end = std::fseek(f, static_cast<long>(e.count * record), SEEK_CUR) != 0;
      continue;
    }
    for (unsigned long long r = 0; r < e.count && !end; ++r)
      if (!checkPlyRowBinary(f, e, info.format == DACPO_PLY_BINARY_BE, pcl, r, end))
        return false;
  }
  return true;
}

/** The PLY header (the support library's parser) and what PCL's reader
 *  makes of it, element counts the file can hold, for ASCII PLY every value
 *  of every element line a number, and the lists PCL's reader takes. */
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
  PclPlyView view;
  if (!checkPlyForPcl(f, fc, *info, view))
    return false;
  if (!checkPlyCounts(fc, *info, file_size - static_cast<long long>(info->data_offset)))
    return false;
  return info->format == DACPO_PLY_ASCII ? checkPlyAscii(f, fc, *info, view)
                                         : checkPlyListsBinary(f, fc, *info, view);
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
