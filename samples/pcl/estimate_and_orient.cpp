// SPDX-License-Identifier: BSD-3-Clause
// estimate_and_orient: PCL's NormalEstimation gives unoriented normals (its
// viewpoint flip cannot orient a whole room); DACPONormalOrientation makes their
// signs globally consistent. The normals stay indexed like the input cloud.
//   estimate_and_orient input.pcd output.pcd
#include <pcl_dacpo/dacpo_normal_orientation.h>

#include <pcl/common/io.h>
#include <pcl/features/normal_3d.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

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

  // One search structure for both steps.
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);

  // 1. Normal axes from PCL (any estimator works: only the axes are used).
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(cloud);
  ne.setSearchMethod(tree);
  ne.setKSearch(16);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  ne.compute(*normals);

  // 2. Orient them. Points whose normal is NaN come out NaN.
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  dacpo.setInputCloud(cloud);
  dacpo.setInputNormals(normals);
  dacpo.setSearchMethod(tree);
  pcl::PointCloud<pcl::Normal> oriented;
  dacpo.compute(oriented);
  if (oriented.empty()) {
    std::cerr << "orientation failed: " << dacpo.getLastError() << "\n";
    return 1;
  }
  std::cout << dacpo.getStats().flipped_blocks << " of " << dacpo.getStats().num_blocks
            << " blocks flipped\n";

  pcl::PointCloud<pcl::PointNormal> out;
  pcl::concatenateFields(*cloud, oriented, out);
  return pcl::io::savePCDFileBinaryCompressed(argv[2], out) < 0 ? 1 : 0;
}
