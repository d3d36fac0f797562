// SPDX-License-Identifier: BSD-3-Clause
// Peer method for the pcl_dacpo benchmark: PCL's flip-toward-viewpoint.
//
//   pcl_viewpoint in.ply out.ply [-normal_k 16] [-threads N]
//
// Reads the points (any normals in the file are ignored), estimates PCA normals
// with pcl::NormalEstimationOMP (normal_k nearest neighbours) and orients each
// normal towards a viewpoint with pcl::flipNormalTowardsViewpoint. No sensor
// position is known for these clouds (the benchmark data has none), so the
// viewpoint is the centroid of the cloud -- what a user without a sensor
// position would do. Writes binary PLY float x y z nx ny nz in input order.
// Last stderr line: "stats: points=N seconds=S viewpoint=x,y,z".
#include <pcl/common/centroid.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include "ply_io.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <string>
#include <vector>

int
main(int argc, char** argv)
{
  if (argc < 3) {
    std::fprintf(
        stderr, "usage: %s in.ply out.ply [-normal_k 16] [-threads N]\n", argv[0]);
    return 2;
  }
  int normal_k = 16;
  unsigned threads = 0;
  for (int i = 3; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "-normal_k" && i + 1 < argc)
      normal_k = std::atoi(argv[++i]);
    else if (a == "-threads" && i + 1 < argc)
      threads = unsigned(std::atoi(argv[++i]));
    else {
      std::fprintf(stderr, "pcl_viewpoint: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  try {
    const std::vector<float> xyz = bench_ply::read_xyz(argv[1]);
    const size_t n = xyz.size() / 3;
    if (n < 3) {
      std::fprintf(stderr, "pcl_viewpoint: too few points in %s\n", argv[1]);
      return 1;
    }
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    cloud->resize(n);
    for (size_t p = 0; p < n; ++p)
      (*cloud)[p] = pcl::PointXYZ(xyz[3 * p], xyz[3 * p + 1], xyz[3 * p + 2]);

    const auto t0 = std::chrono::steady_clock::now();
    Eigen::Vector4f centroid;
    pcl::compute3DCentroid(*cloud, centroid);
    pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne(threads);
    ne.setInputCloud(cloud);
    ne.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(
        new pcl::search::KdTree<pcl::PointXYZ>));
    ne.setKSearch(normal_k);
    // computeFeature calls flipNormalTowardsViewpoint(point, vpx, vpy, vpz, ...) per
    // point.
    ne.setViewPoint(centroid[0], centroid[1], centroid[2]);
    pcl::PointCloud<pcl::Normal> normals;
    ne.compute(normals);
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    std::vector<float> out(3 * n, std::numeric_limits<float>::quiet_NaN());
    for (size_t p = 0; p < n && p < normals.size(); ++p) {
      out[3 * p] = normals[p].normal_x;
      out[3 * p + 1] = normals[p].normal_y;
      out[3 * p + 2] = normals[p].normal_z;
    }
    bench_ply::write_xyz_normals(
        argv[2],
        xyz,
        out,
        "normals: PCL NormalEstimation(k=" + std::to_string(normal_k) +
            ") flipped towards the centroid");
    std::fprintf(stderr,
                 "stats: points=%zu seconds=%.3f viewpoint=%.4f,%.4f,%.4f pcl=%s\n",
                 n,
                 secs,
                 double(centroid[0]),
                 double(centroid[1]),
                 double(centroid[2]),
                 PCL_VERSION_PRETTY);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcl_viewpoint: %s\n", e.what());
    return 1;
  }
  return 0;
}
