/* SPDX-License-Identifier: BSD-3-Clause */
/* Shared by the pcl_dacpo_* tools: the fields of a pcl::PCLPointCloud2 read
 * as numbers of any type, removed and appended (data repacked), a local frame
 * for float work, and coloured copies for pcl_viewer. Header-only, tools only
 * (not installed). */
#pragma once

#include <pcl/common/io.h>
#include <pcl/conversions.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace dacpo_tool {

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

} // namespace dacpo_tool
