// SPDX-License-Identifier: BSD-3-Clause
// Minimal PLY reader/writer for the benchmark peers (bench/peers/*.cpp).
// Reads the x y z of the "vertex" element from ascii or binary_little_endian
// PLY with any scalar property types (other properties are skipped); writes
// binary_little_endian float x y z nx ny nz, which pcl_dacpo_eval reads.
// Points keep the file order, so predictions line up with the ground truth.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace bench_ply {

struct Prop {
  std::string name;
  int size = 0;    // bytes
  char kind = 'f'; // 'i' signed, 'u' unsigned, 'f' float
};

inline Prop
make_prop(const std::string& type, const std::string& name)
{
  Prop p;
  p.name = name;
  if (type == "char" || type == "int8") {
    p.size = 1;
    p.kind = 'i';
  }
  else if (type == "uchar" || type == "uint8") {
    p.size = 1;
    p.kind = 'u';
  }
  else if (type == "short" || type == "int16") {
    p.size = 2;
    p.kind = 'i';
  }
  else if (type == "ushort" || type == "uint16") {
    p.size = 2;
    p.kind = 'u';
  }
  else if (type == "int" || type == "int32") {
    p.size = 4;
    p.kind = 'i';
  }
  else if (type == "uint" || type == "uint32") {
    p.size = 4;
    p.kind = 'u';
  }
  else if (type == "float" || type == "float32") {
    p.size = 4;
    p.kind = 'f';
  }
  else if (type == "double" || type == "float64") {
    p.size = 8;
    p.kind = 'f';
  }
  else
    throw std::runtime_error("unsupported PLY property type '" + type + "'");
  return p;
}

inline double
decode(const unsigned char* b, const Prop& p)
{
  // PLY binary_little_endian; this host is little endian (x86-64, aarch64).
  switch (p.size) {
  case 1:
    return p.kind == 'i' ? double(int8_t(b[0])) : double(b[0]);
  case 2: {
    uint16_t v;
    std::memcpy(&v, b, 2);
    return p.kind == 'i' ? double(int16_t(v)) : double(v);
  }
  case 4: {
    if (p.kind == 'f') {
      float f;
      std::memcpy(&f, b, 4);
      return f;
    }
    uint32_t v;
    std::memcpy(&v, b, 4);
    return p.kind == 'i' ? double(int32_t(v)) : double(v);
  }
  default: {
    double d;
    std::memcpy(&d, b, 8);
    return d;
  }
  }
}

// The header's format and the "vertex" element's properties and count.
struct Header {
  std::string format;
  std::vector<Prop> props; // of the "vertex" element
  size_t count = 0;        // number of vertices
};

// Parses the PLY header (after the "ply" line) up to end_header.
inline Header
read_header(std::istream& in, const std::string& path)
{
  Header h;
  std::string line;
  bool in_vertex = false, seen_vertex = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r')
      line.pop_back();
    std::istringstream ss(line);
    std::string word;
    ss >> word;
    if (word == "format") {
      ss >> h.format;
    }
    else if (word == "element") {
      std::string name;
      size_t n = 0;
      ss >> name >> n;
      if (name == "vertex") {
        h.count = n;
        in_vertex = true;
        seen_vertex = true;
      }
      else {
        if (!seen_vertex && n > 0)
          throw std::runtime_error(path + ": element '" + name +
                                   "' before 'vertex' is not supported");
        in_vertex = false;
      }
    }
    else if (word == "property" && in_vertex) {
      std::string type, name;
      ss >> type;
      if (type == "list")
        throw std::runtime_error(path + ": list property in 'vertex'");
      ss >> name;
      h.props.push_back(make_prop(type, name));
    }
    else if (word == "end_header") {
      break;
    }
  }
  return h;
}

// Reads count binary_little_endian vertices, keeping props idx[0..2] as x y z.
inline void
read_binary_xyz(std::istream& in,
                const std::string& path,
                const Header& h,
                const int idx[3],
                size_t stride,
                std::vector<float>& xyz)
{
  const std::vector<Prop>& props = h.props;
  const size_t count = h.count;
  std::vector<size_t> offset(props.size());
  size_t o = 0;
  for (size_t i = 0; i < props.size(); ++i) {
    offset[i] = o;
    o += size_t(props[i].size);
  }
  std::vector<unsigned char> buf(stride * count);
  in.read(reinterpret_cast<char*>(buf.data()), std::streamsize(buf.size()));
  if (size_t(in.gcount()) != buf.size())
    throw std::runtime_error(path + ": file is truncated");
  for (size_t p = 0; p < count; ++p)
    for (int c = 0; c < 3; ++c)
      xyz[3 * p + c] = float(decode(&buf[p * stride + offset[idx[c]]], props[idx[c]]));
}

// Reads count ascii vertices, keeping props ix, iy, iz as x y z.
inline void
read_ascii_xyz(std::istream& in,
               const std::string& path,
               const Header& h,
               int ix,
               int iy,
               int iz,
               std::vector<float>& xyz)
{
  for (size_t p = 0; p < h.count; ++p) {
    for (size_t i = 0; i < h.props.size(); ++i) {
      double v;
      if (!(in >> v))
        throw std::runtime_error(path + ": file is truncated");
      if (int(i) == ix)
        xyz[3 * p] = float(v);
      if (int(i) == iy)
        xyz[3 * p + 1] = float(v);
      if (int(i) == iz)
        xyz[3 * p + 2] = float(v);
    }
  }
}

// Returns x y z triples (3 * count floats).
inline std::vector<float>
read_xyz(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error("cannot open " + path);
  std::string line;
  std::getline(in, line);
  if (line.rfind("ply", 0) != 0)
    throw std::runtime_error(path + ": not a PLY file");
  const Header h = read_header(in, path);
  const std::vector<Prop>& props = h.props;
  int ix = -1, iy = -1, iz = -1;
  size_t stride = 0;
  for (size_t i = 0; i < props.size(); ++i) {
    if (props[i].name == "x")
      ix = int(i);
    if (props[i].name == "y")
      iy = int(i);
    if (props[i].name == "z")
      iz = int(i);
    stride += size_t(props[i].size);
  }
  if (ix < 0 || iy < 0 || iz < 0)
    throw std::runtime_error(path + ": no x y z vertex properties");
  std::vector<float> xyz(3 * h.count);
  if (h.format == "binary_little_endian") {
    const int idx[3] = {ix, iy, iz};
    read_binary_xyz(in, path, h, idx, stride, xyz);
  }
  else if (h.format == "ascii") {
    read_ascii_xyz(in, path, h, ix, iy, iz, xyz);
  }
  else {
    throw std::runtime_error(path + ": unsupported PLY format '" + h.format + "'");
  }
  return xyz;
}

inline void
write_xyz_normals(const std::string& path,
                  const std::vector<float>& xyz,
                  const std::vector<float>& normals,
                  const std::string& comment)
{
  std::ofstream out(path, std::ios::binary);
  if (!out)
    throw std::runtime_error("cannot write " + path);
  const size_t count = xyz.size() / 3;
  out << "ply\nformat binary_little_endian 1.0\ncomment " << comment
      << "\nelement vertex " << count
      << "\nproperty float x\nproperty float y\nproperty float z\n"
         "property float nx\nproperty float ny\nproperty float nz\nend_header\n";
  std::vector<float> row(6);
  for (size_t p = 0; p < count; ++p) {
    for (int c = 0; c < 3; ++c) {
      row[size_t(c)] = xyz[3 * p + size_t(c)];
      row[3 + size_t(c)] = normals[3 * p + size_t(c)];
    }
    out.write(reinterpret_cast<const char*>(row.data()), 6 * sizeof(float));
  }
  if (!out)
    throw std::runtime_error("write failed: " + path);
}

} // namespace bench_ply
