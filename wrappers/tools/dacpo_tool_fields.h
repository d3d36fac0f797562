/* SPDX-License-Identifier: BSD-3-Clause */
/* Shared by the pcl_dacpo_* tools: the fields of a pcl::PCLPointCloud2 read
 * as numbers of any type, removed and appended (data repacked), a local frame
 * for float work, and coloured copies for pcl_viewer. The templates are here,
 * the rest in dacpo_tool_fields.cpp (library dacpo_tool_io); tools only (not
 * installed). */
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
bool
hasFields(const pcl::PCLPointCloud2& cloud, std::initializer_list<const char*> names);

/** Value of a numeric field element as double. */
double
readValue(const std::uint8_t* p, std::uint8_t datatype);

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

LocalFrame
localFrame(const std::vector<double>& xyz);

/** Copy of \a in without the named fields (data repacked). */
pcl::PCLPointCloud2
removeFields(const pcl::PCLPointCloud2& in, std::initializer_list<const char*> names);

/** Copy of \a in with 4-byte fields of one \a datatype (FLOAT32, INT32 or
 *  UINT32) appended after the existing ones; \a values holds names.size()
 *  4-byte values per point. */
pcl::PCLPointCloud2
appendFields4(const pcl::PCLPointCloud2& in,
              const std::vector<std::string>& names,
              std::uint8_t datatype,
              const void* values);

/** Copy of \a in with FLOAT32 fields appended after the existing ones;
 *  \a values holds names.size() floats per point. */
pcl::PCLPointCloud2
appendFloatFields(const pcl::PCLPointCloud2& in,
                  const std::vector<std::string>& names,
                  const std::vector<float>& values);

/** Copy of \a in with INT32 fields appended after the existing ones;
 *  \a values holds names.size() integers per point. */
pcl::PCLPointCloud2
appendInt32Fields(const pcl::PCLPointCloud2& in,
                  const std::vector<std::string>& names,
                  const std::vector<std::int32_t>& values);

/** Reads one named numeric field of every point as int32 (rounded toward
 *  zero; NaN and out-of-range values become -1). The field must exist. */
std::vector<std::int32_t>
readInt32Field(const pcl::PCLPointCloud2& cloud, const char* name);

/** Reads one named numeric field of every point as float. The field must exist. */
std::vector<float>
readFloatField(const pcl::PCLPointCloud2& cloud, const char* name);

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
pcl::PCLPointCloud2
normalsColored(const pcl::PCLPointCloud2& in);

} // namespace dacpo_tool
