// SPDX-License-Identifier: BSD-3-Clause
// orient_pcd: load a PCD, orient its normals with pcl::DACPONormalOrientation
// (PCA normals estimated inside), save x y z + normals as PCD.
//   orient_pcd input.pcd output.pcd
#include <pcl_dacpo/dacpo_normal_orientation.h>

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <iostream>

int
main(int argc, char** argv)
{
  if (argc != 3) {
    std::cerr << "usage: " << argv[0] << " input.pcd output.pcd\n";
    return 1;
  }
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  if (pcl::io::loadPCDFile(argv[1], *cloud) < 0 || cloud->empty()) {
    std::cerr << "cannot read points from " << argv[1] << "\n";
    return 1;
  }

  // PointXYZ in, PointNormal out: x, y, z are copied, normals and curvature set.
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::PointNormal> dacpo;
  dacpo.setInputCloud(cloud);
  dacpo.setKSearch(10); // neighbour graph (the default)
  dacpo.setNormalK(16); // PCA normals, since none are given
  pcl::PointCloud<pcl::PointNormal> oriented;
  dacpo.compute(oriented);
  if (oriented.empty()) {
    std::cerr << "orientation failed: " << dacpo.getLastError() << "\n";
    return 1;
  }

  const dacpo_stats stats = dacpo.getStats();
  std::cout << stats.input_points << " points, " << stats.num_blocks << " blocks, "
            << stats.flipped_blocks << " flipped, " << stats.total_seconds << " s\n";
  return pcl::io::savePCDFileBinaryCompressed(argv[2], oriented) < 0 ? 1 : 0;
}
