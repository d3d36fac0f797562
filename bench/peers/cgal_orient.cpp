// SPDX-License-Identifier: BSD-3-Clause
// Peer method for the pcl_dacpo benchmark: CGAL's normal orientation.
//
//   cgal_orient in.ply out.ply [-normal_k 16] [-k 10]
//
// Reads the points (any normals in the file are ignored), estimates PCA normals
// with CGAL::pca_estimate_normals (normal_k neighbours) and orients them with
// CGAL::mst_orient_normals (k neighbours; Hoppe et al. 1992: the highest point
// is oriented upwards and its sign propagated along a minimum spanning tree of
// the Riemannian graph). mst_orient_normals moves the points it could not reach
// to the end of the range and returns an iterator to the first of them; their
// normals keep the arbitrary PCA sign. They are counted and reported; the output
// still holds every point, in input order, with the normal CGAL left it.
// Last stderr line: "stats: points=N seconds=S unoriented=U" (S = estimate +
// orient, without file I/O).
#include "ply_io.hpp"
#include <CGAL/mst_orient_normals.h>
#include <CGAL/pca_estimate_normals.h>
#include <CGAL/property_map.h>
#include <CGAL/Simple_cartesian.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <tuple>
#include <vector>

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using Item = std::tuple<Point, Vector, size_t>; // position, normal, input index
using PointMap = CGAL::Nth_of_tuple_property_map<0, Item>;
using NormalMap = CGAL::Nth_of_tuple_property_map<1, Item>;

int
main(int argc, char** argv)
{
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s in.ply out.ply [-normal_k 16] [-k 10]\n", argv[0]);
    return 2;
  }
  unsigned normal_k = 16, k = 10;
  for (int i = 3; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "-normal_k" && i + 1 < argc)
      normal_k = unsigned(std::atoi(argv[++i]));
    else if (a == "-k" && i + 1 < argc)
      k = unsigned(std::atoi(argv[++i]));
    else {
      std::fprintf(stderr, "cgal_orient: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  try {
    const std::vector<float> xyz = bench_ply::read_xyz(argv[1]);
    const size_t n = xyz.size() / 3;
    if (n < 3) {
      std::fprintf(stderr, "cgal_orient: too few points in %s\n", argv[1]);
      return 1;
    }
    std::vector<Item> items;
    items.reserve(n);
    for (size_t p = 0; p < n; ++p)
      items.emplace_back(
          Point(xyz[3 * p], xyz[3 * p + 1], xyz[3 * p + 2]), Vector(0, 0, 0), p);

    const auto t0 = std::chrono::steady_clock::now();
    CGAL::pca_estimate_normals<CGAL::Sequential_tag>(
        items,
        normal_k,
        CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()));
    auto first_unoriented = CGAL::mst_orient_normals(
        items, k, CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()));
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const size_t unoriented = size_t(items.end() - first_unoriented);

    std::vector<float> normals(3 * n);
    for (const Item& it : items) { // back to input order
      const Vector& v = std::get<1>(it);
      const size_t p = std::get<2>(it);
      normals[3 * p] = float(v.x());
      normals[3 * p + 1] = float(v.y());
      normals[3 * p + 2] = float(v.z());
    }
    bench_ply::write_xyz_normals(
        argv[2],
        xyz,
        normals,
        "normals: CGAL pca_estimate_normals(k=" + std::to_string(normal_k) +
            ") + mst_orient_normals(k=" + std::to_string(k) + "); " +
            std::to_string(unoriented) + " points unoriented");
    std::fprintf(stderr,
                 "stats: points=%zu seconds=%.3f unoriented=%zu cgal=%s\n",
                 n,
                 secs,
                 unoriented,
                 CGAL_VERSION_STR);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cgal_orient: %s\n", e.what());
    return 1;
  }
  return 0;
}
