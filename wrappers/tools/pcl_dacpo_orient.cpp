/* SPDX-License-Identifier: BSD-3-Clause */
/* pcl_dacpo_orient: orient the normals of a .pcd/.ply scan with DACPO.
 * Laid out like PCL's tools/normal_estimation.cpp: printHelp, loadCloud,
 * compute, saveCloud, main. Every input field is kept; normal_x/y/z and
 * curvature are added (or replaced). */
#include <dacpo/dacpo.h>

#include <pcl_dacpo/dacpo_normal_orientation.h>

#include <pcl/common/io.h>
#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/console/time.h>
#include <pcl/point_types.h>

#include "dacpo_tool_io.h"

#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <unistd.h>

using namespace pcl::console;

namespace {

/* Reports go to stderr (stdout stays free for pipes) and -q silences them. */
bool g_verbose = true;

template <typename... Args>
void
info(const char* format, Args... args)
{
  if (g_verbose)
    print_info(stderr, format, args...);
}

template <typename... Args>
void
value(const char* format, Args... args)
{
  if (g_verbose)
    print_value(stderr, format, args...);
}

void
highlight(const char* text)
{
  if (g_verbose)
    print_highlight(stderr, "%s", text);
}

struct Options {
  dacpo_params params;
  bool estimate = false;
  bool quiet = false;
};

void
printHelp(int, char** argv)
{
  dacpo_params d;
  dacpo_params_init(&d);
  print_error("Syntax is: %s input.{pcd,ply} output.{pcd,ply} <options>\n", argv[0]);
  print_info("  Orients the normals of an open scene scan with DACPO (TOG 2025).\n");
  print_info("  Every input field is kept; normal_x normal_y normal_z curvature are\n");
  print_info("  written (replaced if present). PCD is written binary compressed, PLY "
             "binary.\n");
  print_info("  where options are:\n");
  print_info(
      "                     -k X        = neighbours of the k-NN graph (default: ");
  print_value("%zu", d.k);
  print_info(")\n");
  print_info("                     -normal_k X = neighbours of PCA normals when "
             "estimated (default: ");
  print_value("%zu", d.normal_k);
  print_info(")\n");
  print_info("                     -estimate   = estimate PCA normals even if the "
             "input has normal_x/y/z\n");
  print_info("                                   (without normals in the input they "
             "are always estimated)\n");
  print_info(
      "                     -blocks X   = number of blocks, 0 = automatic (default: ");
  print_value("%zu", d.num_blocks);
  print_info(")\n");
  print_info("                     -c X        = dipole exponent c, 4 clean / 2 noisy "
             "(default: ");
  print_value("%g", d.dipole_c);
  print_info(")\n");
  print_info("                     -orders X   = randomized dipole propagation orders "
             "(default: ");
  print_value("%zu", d.dipole_orders);
  print_info(")\n");
  print_info(
      "                     -ring X     = block overlap ring in k-NN hops (default: ");
  print_value("%zu", d.ring_hops);
  print_info(")\n");
  print_info(
      "                     -no_ipsr    = skip the iterative Poisson refinement\n");
  print_info(
      "                     -weights S  = block edge weights: dipole | vcr (default: ");
  print_value("%s", d.edge_weight == DACPO_WEIGHT_VCR ? "vcr" : "dipole");
  print_info(")\n");
  print_info(
      "                     -time_limit X = seconds for the 0-1 program (default: ");
  print_value("%g", d.solver_time_limit);
  print_info(")\n");
  print_info("                     -seed X     = random seed (default: ");
  print_value("%llu", static_cast<unsigned long long>(d.seed));
  print_info(")\n");
  print_info(
      "                     -threads X  = worker threads, 0 = all cores (default: ");
  print_value("%u", d.num_threads);
  print_info(")\n");
  print_info("                     -q          = quiet: errors only\n");
  print_info("\nExample:\n  %s scan.ply oriented.pcd -k 10\n", argv[0]);
  print_info("View the result with:\n");
  print_info("  pcl_viewer output.pcd -normals 10 -normals_scale 0.05\n");
}

bool
loadCloud(const std::string& filename, pcl::PCLPointCloud2& cloud)
{
  TicToc tt;
  highlight("Loading ");
  value("%s ", filename.c_str());
  tt.tic();
  std::string error;
  if (!dacpo_tool::loadCloud2(filename, cloud, error)) {
    info("\n");
    print_error("Error: %s\n", error.c_str());
    return false;
  }
  info("[done, ");
  value("%g", tt.toc());
  info(" ms : ");
  value("%u", cloud.width * cloud.height);
  info(" points]\n");
  info("Available dimensions: ");
  value("%s\n", pcl::getFieldsList(cloud).c_str());
  return true;
}

/* Progress on one terminal line: "\r  dipole  42%". */
struct ProgressLine {
  int last_stage = -1;
  int last_percent = -1;
  bool
  operator()(dacpo_stage stage, double fraction)
  {
    const int percent = static_cast<int>(fraction * 100.0 + 0.5);
    if (static_cast<int>(stage) == last_stage && percent == last_percent)
      return true;
    last_stage = static_cast<int>(stage);
    last_percent = percent;
    std::fprintf(stderr, "\r  %-12s %3d%%", dacpo_stage_name(stage), percent);
    std::fflush(stderr);
    return true;
  }
};

bool
compute(const pcl::PCLPointCloud2& input,
        const Options& options,
        pcl::PCLPointCloud2& output)
{
  const std::size_t n = static_cast<std::size_t>(input.width) * input.height;
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
  const std::vector<float> coords = dacpo_tool::readTriplet(input, "x", "y", "z");
  /* Unorganized on purpose: PCL would pick OrganizedNeighbor for an organized
   * cloud, which needs a projective sensor. The output keeps the input's
   * width x height. */
  xyz->resize(n);
  xyz->is_dense = false;
  for (std::size_t i = 0; i < n; ++i)
    (*xyz)[i].getVector3fMap() << coords[3 * i], coords[3 * i + 1], coords[3 * i + 2];

  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  dacpo.setInputCloud(xyz);
  dacpo.setParameters(options.params);

  const bool has_normals =
      dacpo_tool::hasFields(input, {"normal_x", "normal_y", "normal_z"});
  if (has_normals && !options.estimate) {
    const std::vector<float> nv =
        dacpo_tool::readTriplet(input, "normal_x", "normal_y", "normal_z");
    pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
    normals->resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      (*normals)[i].normal_x = nv[3 * i];
      (*normals)[i].normal_y = nv[3 * i + 1];
      (*normals)[i].normal_z = nv[3 * i + 2];
      (*normals)[i].curvature = 0.0f;
    }
    if (dacpo_tool::hasFields(input, {"curvature"})) {
      const int f = pcl::getFieldIndex(input, "curvature");
      for (std::size_t i = 0; i < n; ++i)
        (*normals)[i].curvature = static_cast<float>(dacpo_tool::readValue(
            &input.data[i * input.point_step + input.fields[f].offset],
            input.fields[f].datatype));
    }
    dacpo.setInputNormals(normals);
    info("Orienting the input normals (k = ");
  }
  else {
    info("%s PCA normals (normal_k = ",
         has_normals ? "Re-estimating" : "No normals in the input: estimating");
    value("%zu", options.params.normal_k);
    info(", k = ");
  }
  value("%zu", options.params.k);
  info(")\n");

  ProgressLine line;
  const bool show_progress = !options.quiet && isatty(2);
  if (show_progress)
    dacpo.setProgressCallback(std::ref(line));

  TicToc tt;
  tt.tic();
  pcl::PointCloud<pcl::Normal> normals_out;
  dacpo.compute(normals_out);
  if (show_progress)
    std::fprintf(stderr, "\r%30s\r", "");
  if (normals_out.size() != n) {
    print_error("Error: orientation failed: %s: %s\n",
                dacpo_status_string(dacpo.getLastStatus()),
                dacpo.getLastError().c_str());
    return false;
  }
  const double ms = tt.toc();

  const dacpo_stats s = dacpo.getStats();
  info("Oriented ");
  value("%zu", s.input_points);
  info(" points (");
  value("%zu", s.unique_points);
  info(" distinct) in ");
  value("%g", ms);
  info(" ms: ");
  value("%zu", s.num_blocks);
  info(" blocks, ");
  value("%zu", s.num_block_edges);
  info(" block edges, ");
  value("%zu", s.num_components);
  info(" component(s), ");
  value("%zu", s.flipped_blocks);
  info(" blocks flipped, solver ");
  value("%s\n", s.solver_optimal ? "optimal" : "NOT proven optimal");
  info("Stage times [s]:");
  for (int st = 0; st < DACPO_STAGE_COUNT; ++st) {
    info(" %s ", dacpo_stage_name(static_cast<dacpo_stage>(st)));
    value("%.3f", s.stage_seconds[st]);
  }
  info(" | total ");
  value("%.3f\n", s.total_seconds);

  /* Keep every input field except the ones we write, then append ours. */
  pcl::PCLPointCloud2 stripped = dacpo_tool::removeFields(
      input, {"normal_x", "normal_y", "normal_z", "curvature"});
  std::vector<float> values(4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    values[4 * i] = normals_out[i].normal_x;
    values[4 * i + 1] = normals_out[i].normal_y;
    values[4 * i + 2] = normals_out[i].normal_z;
    values[4 * i + 3] = normals_out[i].curvature;
  }
  output = dacpo_tool::appendFloatFields(
      stripped, {"normal_x", "normal_y", "normal_z", "curvature"}, values);
  output.is_dense = normals_out.is_dense && input.is_dense;
  return true;
}

bool
saveCloud(const std::string& filename, const pcl::PCLPointCloud2& output)
{
  TicToc tt;
  tt.tic();
  highlight("Saving ");
  value("%s ", filename.c_str());
  std::string error;
  if (!dacpo_tool::saveCloud2(filename, output, error)) {
    info("\n");
    print_error("Error: %s\n", error.c_str());
    return false;
  }
  info("[done, ");
  value("%g", tt.toc());
  info(" ms : ");
  value("%u", output.width * output.height);
  info(" points]\n");
  return true;
}

bool
parseOptions(int argc, char** argv, Options& o)
{
  dacpo_params_init(&o.params);
  std::string error;
  std::uint64_t k = o.params.k, normal_k = o.params.normal_k,
                blocks = o.params.num_blocks, orders = o.params.dipole_orders,
                ring = o.params.ring_hops, seed = o.params.seed,
                threads = o.params.num_threads;
  double c = o.params.dipole_c, time_limit = o.params.solver_time_limit;
  if (!dacpo_tool::parseUnsigned(argc, argv, "-k", k, error) ||
      !dacpo_tool::parseUnsigned(argc, argv, "-normal_k", normal_k, error) ||
      !dacpo_tool::parseUnsigned(argc, argv, "-blocks", blocks, error) ||
      !dacpo_tool::parseUnsigned(argc, argv, "-orders", orders, error) ||
      !dacpo_tool::parseUnsigned(argc, argv, "-ring", ring, error) ||
      !dacpo_tool::parseUnsigned(argc, argv, "-seed", seed, error) ||
      !dacpo_tool::parseUnsigned(argc, argv, "-threads", threads, error) ||
      !dacpo_tool::parseDouble(argc, argv, "-c", c, error) ||
      !dacpo_tool::parseDouble(argc, argv, "-time_limit", time_limit, error)) {
    print_error("Error: %s\n", error.c_str());
    return false;
  }
  if (threads > 4096) {
    print_error("Error: -threads %llu is too large\n",
                static_cast<unsigned long long>(threads));
    return false;
  }
  o.params.k = k;
  o.params.normal_k = normal_k;
  o.params.num_blocks = blocks;
  o.params.dipole_orders = orders;
  o.params.ring_hops = ring;
  o.params.seed = seed;
  o.params.num_threads = static_cast<unsigned>(threads);
  o.params.dipole_c = c;
  o.params.solver_time_limit = time_limit;
  o.params.ipsr_enabled = find_switch(argc, argv, "-no_ipsr") ? 0 : 1;
  std::string weights;
  if (parse_argument(argc, argv, "-weights", weights) >= 0) {
    if (weights == "dipole")
      o.params.edge_weight = DACPO_WEIGHT_DIPOLE_BOUNDARY;
    else if (weights == "vcr")
      o.params.edge_weight = DACPO_WEIGHT_VCR;
    else {
      print_error("Error: -weights must be dipole or vcr, got '%s'\n", weights.c_str());
      return false;
    }
  }
  o.estimate = find_switch(argc, argv, "-estimate");
  o.quiet = find_switch(argc, argv, "-q");
  o.params.estimate_normals = 0; /* decided per input in compute() */
  dacpo_params check = o.params;
  check.estimate_normals = 1;
  char message[256];
  if (dacpo_params_validate(&check, message, sizeof(message)) != DACPO_OK) {
    print_error("Error: %s\n", message);
    return false;
  }
  return true;
}

} // namespace

int
main(int argc, char** argv)
{
  if (argc < 3 || find_switch(argc, argv, "-h") || find_switch(argc, argv, "--help")) {
    print_info("Orient normals with DACPO. For more information, use: %s -h\n",
               argv[0]);
    printHelp(argc, argv);
    return argc < 3 ? 1 : 0;
  }
  const std::vector<std::string> files = dacpo_tool::fileArguments(argc, argv);
  if (files.size() != 2) {
    print_error("Need one input and one output file (.pcd or .ply), got %zu.\n",
                files.size());
    printHelp(argc, argv);
    return 1;
  }
  Options options;
  if (!parseOptions(argc, argv, options))
    return 1;
  if (options.quiet) {
    g_verbose = false;
    setVerbosityLevel(L_ERROR);
  }

  pcl::PCLPointCloud2 cloud;
  if (!loadCloud(files[0], cloud))
    return 1;
  if (cloud.width * cloud.height == 0) {
    print_error("Error: '%s' has no points\n", files[0].c_str());
    return 1;
  }
  pcl::PCLPointCloud2 output;
  if (!compute(cloud, options, output))
    return 1;
  if (!saveCloud(files[1], output))
    return 1;
  return 0;
}
