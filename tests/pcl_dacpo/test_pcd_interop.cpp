// SPDX-License-Identifier: BSD-3-Clause
// The plain-C PCD reader/writer (wrappers/support/dacpo_pcd.c, used by
// pcl_dacpo_orient_mpi, which does not link PCL) against PCL's own PCD I/O:
// every DATA kind PCL writes is read back to the same values, and what we write
// PCL reads back bit for bit.
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <gtest/gtest.h>

extern "C" {
#include "dacpo_pcd.h"
}

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <unistd.h>

namespace {

std::string
TempPath(const std::string& name)
{
  return testing::TempDir() + "dacpo_pcd_interop_" + std::to_string(getpid()) + "_" +
         name;
}

// PointXYZRGBNormal: PCL writes its padding as `_` fields and rgb and
// curvature between the fields we read, so the layout is not the trivial one.
pcl::PointCloud<pcl::PointXYZRGBNormal>
Cloud(int n)
{
  pcl::PointCloud<pcl::PointXYZRGBNormal> c;
  for (int i = 0; i < n; ++i) {
    pcl::PointXYZRGBNormal p;
    p.x = 0.37f * i - 11.0f;
    p.y = std::sin(0.1f * i);
    p.z = 1.0f / (1 + i);
    p.r = static_cast<std::uint8_t>(i);
    p.g = 7;
    p.b = 200;
    const float a = 0.05f * i;
    p.normal_x = std::cos(a);
    p.normal_y = std::sin(a);
    p.normal_z = 0.0f;
    p.curvature = 0.5f;
    c.push_back(p);
  }
  return c;
}

} // namespace

TEST(DacpoPcdInterop, ReadsWhatPclWritesInEveryDataKind)
{
  const auto cloud = Cloud(5000); // repeats enough for LZF back references
  const std::string path = TempPath("pcl.pcd");
  for (int kind = 0; kind < 3; ++kind) {
    pcl::PCDWriter w;
    const int rc = kind == 0   ? w.writeASCII(path, cloud, 9)
                   : kind == 1 ? w.writeBinary(path, cloud)
                               : w.writeBinaryCompressed(path, cloud);
    ASSERT_EQ(rc, 0);
    dacpo_ply_cloud c;
    char err[512] = "";
    ASSERT_EQ(dacpo_pcd_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK)
        << "kind " << kind << ": " << err;
    ASSERT_EQ(c.n, cloud.size());
    ASSERT_NE(c.normals, nullptr);
    for (std::size_t i = 0; i < c.n; ++i) {
      const auto& p = cloud[i];
      const float want[6] = {p.x, p.y, p.z, p.normal_x, p.normal_y, p.normal_z};
      for (int d = 0; d < 6; ++d) {
        const float got = d < 3 ? c.xyz[3 * i + d] : c.normals[3 * i + d - 3];
        // ascii with 9 digits round-trips floats exactly, too
        ASSERT_EQ(got, want[d]) << "kind " << kind << " point " << i << " value " << d;
      }
    }
    dacpo_ply_cloud_free(&c);
  }
  std::remove(path.c_str());
}

TEST(DacpoPcdInterop, PclReadsWhatWeWrite)
{
  const auto cloud = Cloud(300);
  std::vector<float> xyz, nrm;
  for (const auto& p : cloud) {
    xyz.insert(xyz.end(), {p.x, p.y, p.z});
    nrm.insert(nrm.end(), {p.normal_x, p.normal_y, p.normal_z});
  }
  const std::string path = TempPath("ours.pcd");
  char err[256];
  ASSERT_EQ(dacpo_pcd_write(path.c_str(),
                            xyz.data(),
                            nrm.data(),
                            cloud.size(),
                            "a comment",
                            err,
                            sizeof(err)),
            DACPO_PLY_OK)
      << err;
  pcl::PointCloud<pcl::PointNormal> back;
  ASSERT_EQ(pcl::io::loadPCDFile(path, back), 0);
  ASSERT_EQ(back.size(), cloud.size());
  EXPECT_EQ(back.width, cloud.size());
  EXPECT_EQ(back.height, 1u);
  for (std::size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].x, cloud[i].x);
    EXPECT_EQ(back[i].y, cloud[i].y);
    EXPECT_EQ(back[i].z, cloud[i].z);
    EXPECT_EQ(back[i].normal_x, cloud[i].normal_x);
    EXPECT_EQ(back[i].normal_y, cloud[i].normal_y);
    EXPECT_EQ(back[i].normal_z, cloud[i].normal_z);
  }
  std::remove(path.c_str());
}
