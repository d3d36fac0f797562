/* SPDX-License-Identifier: BSD-3-Clause */
/* The fields of a pcl::PCLPointCloud2 for the pcl_dacpo_* tools
 * (dacpo_tool_fields.h): values of any numeric type, fields removed and
 * appended with the data repacked, the local frame, normal-coloured copies. */
#include "dacpo_tool_fields.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace dacpo_tool {

bool
hasFields(const pcl::PCLPointCloud2& cloud, std::initializer_list<const char*> names)
{
  for (const char* n : names)
    if (pcl::getFieldIndex(cloud, n) < 0)
      return false;
  return true;
}

namespace {
/* One value of type T at p (any alignment). */
template <typename T>
double
load(const std::uint8_t* p)
{
  T v;
  std::memcpy(&v, p, sizeof(T));
  return static_cast<double>(v);
}
} // namespace

double
readValue(const std::uint8_t* p, std::uint8_t datatype)
{
  switch (datatype) {
  case pcl::PCLPointField::INT8:
    return load<std::int8_t>(p);
  case pcl::PCLPointField::UINT8:
    return load<std::uint8_t>(p);
  case pcl::PCLPointField::INT16:
    return load<std::int16_t>(p);
  case pcl::PCLPointField::UINT16:
    return load<std::uint16_t>(p);
  case pcl::PCLPointField::INT32:
    return load<std::int32_t>(p);
  case pcl::PCLPointField::UINT32:
    return load<std::uint32_t>(p);
  case pcl::PCLPointField::FLOAT32:
    return load<float>(p);
  case pcl::PCLPointField::FLOAT64:
    return load<double>(p);
  default:
    return std::numeric_limits<double>::quiet_NaN();
  }
}

LocalFrame
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

pcl::PCLPointCloud2
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

pcl::PCLPointCloud2
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

pcl::PCLPointCloud2
appendFloatFields(const pcl::PCLPointCloud2& in,
                  const std::vector<std::string>& names,
                  const std::vector<float>& values)
{
  return appendFields4(in, names, pcl::PCLPointField::FLOAT32, values.data());
}

pcl::PCLPointCloud2
appendInt32Fields(const pcl::PCLPointCloud2& in,
                  const std::vector<std::string>& names,
                  const std::vector<std::int32_t>& values)
{
  return appendFields4(in, names, pcl::PCLPointField::INT32, values.data());
}

std::vector<std::int32_t>
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

std::vector<float>
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

pcl::PCLPointCloud2
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
