// SPDX-License-Identifier: BSD-3-Clause
// dacpo_tool::saveCloud2 writes binary PLY with the bytes PCL's PLYWriter
// writes, whether it copies the fields itself or hands the cloud to PCL, and
// the file reads back to the same values.
#include "dacpo_tool_io.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <unistd.h>

namespace {

std::string
fileBytes(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string
tempPath(const char* name)
{
  return std::string("/tmp/dacpo_test_tool_io_") + std::to_string(::getpid()) + "_" + name;
}

void
addField(pcl::PCLPointCloud2& c, const char* name, std::uint8_t type, std::uint32_t& offset)
{
  pcl::PCLPointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = type;
  f.count = 1;
  c.fields.push_back(f);
  offset += static_cast<std::uint32_t>(pcl::getFieldSize(type));
}

/* n points: x y z (float), normal_x/y/z (float), a double, an int32, a uint8
 * and a uint16, with 3 bytes of padding at the end of each point; every byte
 * of a point's value differs from the next point's. */
pcl::PCLPointCloud2
mixedCloud(std::uint32_t n, bool with_rgb)
{
  pcl::PCLPointCloud2 c;
  std::uint32_t off = 0;
  for (const char* name : {"x", "y", "z", "normal_x", "normal_y", "normal_z"})
    addField(c, name, pcl::PCLPointField::FLOAT32, off);
  addField(c, "quality", pcl::PCLPointField::FLOAT64, off);
  addField(c, "label", pcl::PCLPointField::INT32, off);
  addField(c, "flag", pcl::PCLPointField::UINT8, off);
  addField(c, "count", pcl::PCLPointField::UINT16, off);
  if (with_rgb)
    addField(c, "rgb", pcl::PCLPointField::FLOAT32, off);
  c.point_step = off + 3;
  c.width = n;
  c.height = 1;
  c.row_step = c.point_step * n;
  c.is_dense = true;
  c.data.assign(static_cast<std::size_t>(c.row_step), 0);
  for (std::uint32_t i = 0; i < n; ++i)
    for (const auto& f : c.fields) {
      std::uint8_t* p = &c.data[static_cast<std::size_t>(i) * c.point_step + f.offset];
      if (f.datatype == pcl::PCLPointField::FLOAT32) {
        const float v = 0.25f * static_cast<float>(i) - 1.5f + static_cast<float>(f.offset);
        std::memcpy(p, &v, sizeof(v));
      }
      else if (f.datatype == pcl::PCLPointField::FLOAT64) {
        const double v = 1e-3 * i + 0.125;
        std::memcpy(p, &v, sizeof(v));
      }
      else if (f.datatype == pcl::PCLPointField::INT32) {
        const std::int32_t v = -7 * static_cast<std::int32_t>(i);
        std::memcpy(p, &v, sizeof(v));
      }
      else if (f.datatype == pcl::PCLPointField::UINT8)
        *p = static_cast<std::uint8_t>(i * 3);
      else {
        const std::uint16_t v = static_cast<std::uint16_t>(i * 257);
        std::memcpy(p, &v, sizeof(v));
      }
    }
  return c;
}

void
expectSameAsPcl(const pcl::PCLPointCloud2& cloud, const char* name)
{
  const std::string ours = tempPath((std::string(name) + "_ours.ply").c_str());
  const std::string pcls = tempPath((std::string(name) + "_pcl.ply").c_str());
  std::string error;
  ASSERT_TRUE(dacpo_tool::saveCloud2(ours, cloud, error)) << error;
  pcl::PLYWriter writer;
  ASSERT_EQ(writer.writeBinary(pcls, cloud, Eigen::Vector4f::Zero(),
                               Eigen::Quaternionf::Identity(), false),
            0);
  const std::string a = fileBytes(ours), b = fileBytes(pcls);
  EXPECT_GT(a.size(), cloud.width * 30u);
  EXPECT_TRUE(a == b) << name << ": " << a.size() << " bytes against PCL's " << b.size();
  std::remove(ours.c_str());
  std::remove(pcls.c_str());
}

} // namespace

TEST(ToolIo, PlyBytesAreThoseOfPclForPlainFields)
{
  expectSameAsPcl(mixedCloud(257, false), "plain");
}

TEST(ToolIo, PlyBytesAreThoseOfPclForColourFields)
{
  expectSameAsPcl(mixedCloud(33, true), "rgb");
}

TEST(ToolIo, PlyReadsBackToTheSameValues)
{
  const pcl::PCLPointCloud2 cloud = mixedCloud(100, false);
  const std::string path = tempPath("roundtrip.ply");
  std::string error;
  ASSERT_TRUE(dacpo_tool::saveCloud2(path, cloud, error)) << error;
  pcl::PCLPointCloud2 back;
  ASSERT_TRUE(dacpo_tool::loadCloud2(path, back, error)) << error;
  std::remove(path.c_str());
  ASSERT_EQ(back.width * back.height, 100u);
  for (const char* name : {"x", "normal_y", "quality", "label", "flag", "count"}) {
    const int a = pcl::getFieldIndex(cloud, name), b = pcl::getFieldIndex(back, name);
    ASSERT_GE(b, 0) << name;
    const std::size_t size = pcl::getFieldSize(cloud.fields[a].datatype);
    ASSERT_EQ(back.fields[b].datatype, cloud.fields[a].datatype) << name;
    for (std::uint32_t i = 0; i < 100; ++i)
      EXPECT_EQ(0, std::memcmp(&cloud.data[i * cloud.point_step + cloud.fields[a].offset],
                               &back.data[i * back.point_step + back.fields[b].offset],
                               size))
          << name << " of point " << i;
  }
}
