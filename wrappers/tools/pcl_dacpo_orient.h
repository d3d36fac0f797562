/* SPDX-License-Identifier: BSD-3-Clause */
/* pcl_dacpo_orient, the tool's own declarations: its options, what a run
 * leaves for the diagnostics, the stderr reports, and the functions of its
 * three files (pcl_dacpo_orient.cpp: load, orient, batch, main;
 * pcl_dacpo_orient_options.cpp: the option table, help and checks;
 * pcl_dacpo_orient_outputs.cpp: the output cloud writers, side files and the
 * stats line). Not installed. */
#ifndef PCL_DACPO_ORIENT_TOOL_H
#define PCL_DACPO_ORIENT_TOOL_H

#include <dacpo/dacpo.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>

#include <cstdint>
#include <string>
#include <vector>

namespace orient_tool {

/* Reports go to stderr (stdout stays free for pipes) and -q silences them. */
inline bool g_verbose = true;

template <typename... Args>
void
info(const char* format, Args... args)
{
  if (g_verbose)
    pcl::console::print_info(stderr, format, args...);
}

template <typename... Args>
void
value(const char* format, Args... args)
{
  if (g_verbose)
    pcl::console::print_value(stderr, format, args...);
}

inline void
highlight(const char* text)
{
  if (g_verbose)
    pcl::console::print_highlight(stderr, "%s", text);
}

/* Edges whose confidence is below this are reported as weak (issue 4). */
constexpr double kLowConfidence = 0.2;

struct Options {
  dacpo_params params;
  bool estimate = false;
  bool quiet = false;
  bool labels = false;               /* -labels: block, component, flip fields */
  std::string edges;                 /* -edges file.csv */
  std::string blocks_colored;        /* -blocks_colored file.{pcd,ply} */
  std::string normals_colored;       /* -normals_colored file.{pcd,ply} */
  std::string input_dir, output_dir; /* batch mode */
  std::string mesh;                  /* -mesh file.ply */
  std::string sign;                  /* -sign free|keep */
  std::string viewpoint;             /* -vp x,y,z */
  double memory = 0.0;               /* -memory: bytes, 0 = in core */
  double tile_halo = 0.0;            /* -tile_halo: metres, 0 = automatic */
  std::uint64_t tile_points = 0;     /* -tiles: points per tile, 0 = from -memory */
  bool separate = false, bridge = false;
};

/* What a run leaves for the diagnostics, in output (= input) point order. */
struct Result {
  std::size_t points = 0; /* input points, skipped ones included */
  dacpo_stats stats;
  std::vector<int> blocks, components;
  std::vector<float> confidence;
  std::vector<std::uint8_t> flips;
  std::vector<dacpo_edge_info> edges;
  std::vector<float> mesh_vertices;
  std::vector<std::int32_t> mesh_triangles;
};

/* pcl_dacpo_orient_options.cpp */
void printHelp(int argc, char** argv);
/* Unknown options and missing values: false with the message. */
bool checkOptions(int argc, char** argv, std::string& error);
/* Every option into o (parameters validated); false after printing why. */
bool parseOptions(int argc, char** argv, Options& o);
/* The arguments that are neither options nor their values. */
std::vector<std::string> fileArguments(int argc, char** argv);

/* pcl_dacpo_orient_outputs.cpp: each prints what it wrote, or the error */
bool saveCloud(const std::string& filename, const pcl::PCLPointCloud2& output);
bool saveEdges(const std::string& filename, const Result& r);
bool saveBlocksColored(const std::string& filename,
                       const pcl::PCLPointCloud2& input,
                       const Result& r);
bool saveMesh(const std::string& filename, const Result& r);
/* Peak resident memory of this process in MiB. */
double peakRssMb();
/* One machine-readable line, printed even with -q (benchmarks grep it). */
void printStats(const Result& result);

} // namespace orient_tool

#endif
