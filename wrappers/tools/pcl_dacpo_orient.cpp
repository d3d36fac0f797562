/* SPDX-License-Identifier: BSD-3-Clause */
/* pcl_dacpo_orient: orient the normals of a .pcd/.ply scan with DACPO.
 * Laid out like PCL's tools/normal_estimation.cpp: printHelp, loadCloud,
 * compute, saveCloud, main. Every input field is kept; normal_x/y/z and
 * curvature are added (or replaced). Diagnostics for tuning: -labels adds the
 * block, component and flip of every point, -edges writes the block-graph edge
 * weights as CSV, -blocks_colored writes one colour per block (darker when the
 * 0-1 program flipped it). A last "stats: ..." line (also with -q) gives the
 * counts, time and peak memory. The options are in pcl_dacpo_orient_options.cpp,
 * the writers in pcl_dacpo_orient_outputs.cpp. */
#include "pcl_dacpo_orient.h"

#include <pcl_dacpo/dacpo_normal_orientation.h>

#include <pcl/common/io.h>
#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/console/time.h>
#include <pcl/point_types.h>

#include "dacpo_paths.h"
#include "dacpo_ply.h"
#include "dacpo_tiled.h"
#include "dacpo_tool_io.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <unistd.h>
#include <vector>

using namespace pcl::console;
using namespace orient_tool;

namespace {

/* Output fields written by -labels; dropped from the input in any case, since
 * labels of an earlier run would be stale. */
const std::vector<std::string> kLabelFields = {"block", "component", "flip"};

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

/* Stages 2 and 3 run in one pass over the blocks (reported as ipsr, or as
 * dipole when iPSR is off): name them both. */
const char*
progressName(dacpo_stage stage)
{
  return stage == DACPO_STAGE_IPSR ? "dipole+ipsr" : dacpo_stage_name(stage);
}

/* Progress to stderr, shown once a run has taken more than a second. On a
 * terminal one line rewritten in place: "\r  dipole+ipsr   42%  elapsed 3.1 s
 * stage left ~4.2 s" (the time left extrapolated from the stage's progress);
 * in a pipe or a log a line per stage and every few seconds. */
struct ProgressLine {
  using Clock = std::chrono::steady_clock;
  static constexpr double kLogEvery = 5.0; /* seconds between lines in a log */
  bool tty = true;
  Clock::time_point start = Clock::now();
  Clock::time_point stage_start = start;
  double last_line = -kLogEvery;
  int last_stage = -1;
  int last_percent = -1;
  bool shown = false;
  bool
  operator()(dacpo_stage stage, double fraction)
  {
    const Clock::time_point now = Clock::now();
    const bool new_stage = static_cast<int>(stage) != last_stage;
    if (new_stage)
      stage_start = now;
    const int percent = static_cast<int>(fraction * 100.0 + 0.5);
    const double elapsed = std::chrono::duration<double>(now - start).count();
    const double in_stage = std::chrono::duration<double>(now - stage_start).count();
    const bool due = tty ? !(!new_stage && percent == last_percent)
                         : new_stage || elapsed - last_line >= kLogEvery;
    last_stage = static_cast<int>(stage);
    if (!due || (!shown && elapsed < 1.0))
      return true;
    last_percent = percent;
    last_line = elapsed;
    shown = true;
    char left[48] = "";
    if (fraction > 0.02 && fraction < 1.0)
      std::snprintf(left, sizeof(left), "  stage left ~%.1f s", in_stage * (1.0 - fraction) / fraction);
    std::fprintf(stderr,
                 tty ? "\r  %-12s %3d%%  elapsed %.1f s%-22s" : "progress: %s %d%% elapsed %.1f s%s\n",
                 progressName(stage),
                 percent,
                 elapsed,
                 left);
    std::fflush(stderr);
    return true;
  }
};

/* The input's points as floats in the local frame. Unorganized on purpose: PCL
 * would pick OrganizedNeighbor for an organized cloud, which needs a projective
 * sensor. The output keeps the input's width x height. */
pcl::PointCloud<pcl::PointXYZ>::Ptr
localCloud(const std::vector<double>& coords,
           const dacpo_tool::LocalFrame& frame,
           std::size_t n)
{
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
  xyz->resize(n);
  xyz->is_dense = false;
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      (*xyz)[i].data[d] =
          static_cast<float>((coords[3 * i + d] - frame.centre[d]) / frame.scale);
  return xyz;
}

/* The input's normals (and curvature, 0 if absent) as a PCL cloud. */
pcl::PointCloud<pcl::Normal>::Ptr
inputNormals(const pcl::PCLPointCloud2& input, std::size_t n)
{
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
  return normals;
}

/* Gives the run the input's normals unless they are absent or -estimate asks
 * for PCA normals; says which. */
void
chooseNormals(const pcl::PCLPointCloud2& input,
              const Options& options,
              std::size_t n,
              pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal>& dacpo)
{
  const bool has_normals =
      dacpo_tool::hasFields(input, {"normal_x", "normal_y", "normal_z"});
  if (has_normals && !options.estimate) {
    dacpo.setInputNormals(inputNormals(input, n));
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
}

/* The run's summary and stage times (not with -q). */
void
printRunSummary(const dacpo_stats& s, double ms)
{
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
}

/* Stats, labels, edges and mesh of the run; the mesh back in the input frame. */
void
collectResult(const pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal>& dacpo,
              const dacpo_tool::LocalFrame& frame,
              std::size_t n,
              Result& result)
{
  result.points = n;
  result.stats = dacpo.getStats();
  result.blocks = dacpo.getBlockLabels();
  result.components = dacpo.getComponentLabels();
  result.confidence = dacpo.getPointConfidence();
  result.flips = dacpo.getBlockFlips();
  result.edges = dacpo.getEdges();
  result.mesh_vertices = dacpo.getMeshVertices();
  for (std::size_t i = 0; i < result.mesh_vertices.size(); ++i)
    result.mesh_vertices[i] =
        static_cast<float>(result.mesh_vertices[i] * frame.scale + frame.centre[i % 3]);
  result.mesh_triangles = dacpo.getMeshTriangles();
}

/* The output cloud: every input field except the ones we write, then the
 * normals and curvature, and with -labels block, component, flip and
 * confidence. */
bool
buildOutput(const pcl::PCLPointCloud2& input,
            const pcl::PointCloud<pcl::Normal>& normals_out,
            const Options& options,
            const Result& result,
            pcl::PCLPointCloud2& output)
{
  const std::size_t n = result.points;
  pcl::PCLPointCloud2 stripped = dacpo_tool::removeFields(input,
                                                          {"normal_x",
                                                           "normal_y",
                                                           "normal_z",
                                                           "curvature",
                                                           "block",
                                                           "component",
                                                           "flip",
                                                           "confidence"});
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
  if (!options.labels)
    return true;
  if (result.blocks.size() != n || result.components.size() != n) {
    print_error("Error: the run left no block labels\n");
    return false;
  }
  std::vector<std::int32_t> labels(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const int b = result.blocks[i];
    labels[3 * i] = b;
    labels[3 * i + 1] = result.components[i];
    labels[3 * i + 2] = b >= 0 && static_cast<std::size_t>(b) < result.flips.size()
                            ? result.flips[b]
                            : -1;
  }
  const bool dense = output.is_dense;
  output = dacpo_tool::appendInt32Fields(output, kLabelFields, labels);
  if (result.confidence.size() == n)
    output = dacpo_tool::appendFloatFields(output, {"confidence"}, result.confidence);
  output.is_dense = dense;
  return true;
}

bool
compute(const pcl::PCLPointCloud2& input,
        const Options& options,
        pcl::PCLPointCloud2& output,
        Result& result)
{
  const std::size_t n = static_cast<std::size_t>(input.width) * input.height;
  const std::vector<double> coords =
      dacpo_tool::readTriplet<double>(input, "x", "y", "z");
  /* Read in double and, where float is at risk (georeferenced offsets, huge
   * or tiny clouds: dacpo_tool::localFrame), moved to a local frame:
   * orientation does not depend on position or scale. The output keeps the
   * input's own coordinates. */
  const dacpo_tool::LocalFrame frame = dacpo_tool::localFrame(coords);

  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  dacpo.setInputCloud(localCloud(coords, frame, n));
  dacpo_params params = options.params;
  for (int d = 0; d < 3; ++d) /* -vp is given in the input's frame */
    params.viewpoint[d] = (params.viewpoint[d] - frame.centre[d]) / frame.scale;
  dacpo.setParameters(params);
  chooseNormals(input, options, n, dacpo);

  ProgressLine line;
  line.tty = isatty(2) != 0;
  const bool show_progress = !options.quiet;
  if (show_progress)
    dacpo.setProgressCallback(std::ref(line));

  TicToc tt;
  tt.tic();
  pcl::PointCloud<pcl::Normal> normals_out;
  dacpo.compute(normals_out);
  if (show_progress && line.tty && line.shown)
    std::fprintf(stderr, "\r%78s\r", "");
  if (normals_out.size() != n) {
    print_error("Error: orientation failed: %s: %s\n",
                dacpo.statusString(dacpo.getLastStatus()),
                dacpo.getLastError().c_str());
    return false;
  }
  const double ms = tt.toc();
  printRunSummary(dacpo.getStats(), ms);
  collectResult(dacpo, frame, n, result);
  return buildOutput(input, normals_out, options, result, output);
}

} // namespace

constexpr int kFitsInCore = -1;

/* -memory / -tiles: a cloud larger than the budget allows is oriented tile by tile
 * from disk (dacpo_tiled.c); kFitsInCore when it fits (the in-core path runs,
 * the answer is the same as without -memory), else 0 / 1. */
int
orientTiled(const std::string& in, const std::string& out, const Options& options)
{
  dacpo_tiled_options t{};
  t.input = in.c_str();
  t.output = out.c_str();
  t.max_points = options.tile_points ? options.tile_points
                                     : dacpo_tiled_points_for_memory(options.memory);
  t.halo = options.tile_halo;
  t.params = dacpo_tiled_params(&options.params);
  char err[512] = "";
  dacpo_ply_rows rows;
  if (dacpo_tool::extension(in) != ".ply" ||
      dacpo_ply_rows_open(in.c_str(), &rows, err, sizeof(err)) != 0) {
    print_error("Error: -memory reads binary PLY: %s\n",
                err[0] ? err : ("'" + in + "' is not a .ply file").c_str());
    return 1;
  }
  if (rows.n <= t.max_points)
    return kFitsInCore;
  if (dacpo_tool::extension(out) != ".ply" || options.labels || !options.edges.empty() ||
      !options.blocks_colored.empty() || !options.mesh.empty() ||
      !options.normals_colored.empty()) {
    print_error("Error: '%s' (%llu points) needs tiles under -memory (at most %llu points "
                "in core): write a .ply, without -labels, -edges, -blocks_colored, -mesh "
                "or -normals_colored\n",
                in.c_str(),
                static_cast<unsigned long long>(rows.n),
                static_cast<unsigned long long>(t.max_points));
    return 1;
  }
  dacpo_tiled_report rep;
  if (dacpo_tiled_orient(&t, &rep, err, sizeof(err)) != 0) {
    print_error("Error: %s\n", err);
    return 1;
  }
  std::fprintf(stderr,
               "tiles: points=%llu tiles=%zu halo=%.4g halo_points=%llu largest_tile=%llu "
               "flipped_tiles=%zu blocks=%zu seconds_sample=%.2f seconds_route=%.2f "
               "seconds_tiles=%.2f seconds_join=%.2f seconds_flip=%.2f peak_rss_mb=%.1f\n",
               static_cast<unsigned long long>(rep.points),
               rep.tiles,
               rep.halo,
               static_cast<unsigned long long>(rep.halo_points),
               static_cast<unsigned long long>(rep.largest_tile),
               rep.flipped_tiles,
               rep.blocks,
               rep.seconds[0],
               rep.seconds[1],
               rep.seconds[2],
               rep.seconds[3],
               rep.seconds[4],
               peakRssMb());
  return 0;
}

/* One input to one output (and the side outputs), then the stats line;
 * 0 on success, 1 on failure (the message is printed). */
int
orientFile(const std::string& in, const std::string& out, const Options& options)
{
  /* every output's folder is checked before the work, not after it */
  for (const std::string* path :
       {&out, &options.edges, &options.blocks_colored, &options.normals_colored, &options.mesh}) {
    char err[512];
    if (!path->empty() && dacpo_output_path_check(path->c_str(), err, sizeof(err)) != 0) {
      print_error("Error: %s\n", err);
      return 1;
    }
  }
  if (options.memory > 0.0 || options.tile_points > 0) {
    const int tiled = orientTiled(in, out, options);
    if (tiled != kFitsInCore)
      return tiled;
  }
  pcl::PCLPointCloud2 cloud;
  if (!loadCloud(in, cloud))
    return 1;
  if (cloud.width * cloud.height == 0) {
    print_error("Error: '%s' has no points\n", in.c_str());
    return 1;
  }
  pcl::PCLPointCloud2 output;
  Result result;
  if (!compute(cloud, options, output, result))
    return 1;
  if (!options.mesh.empty() && result.mesh_triangles.empty()) {
    print_error(
        "Error: no surface mesh for '%s': its %zu points are too few or too sparse "
        "for a Poisson surface (blocks need at least 32 points); nothing written\n",
        in.c_str(),
        result.points);
    return 1;
  }
  if (!saveCloud(out, output))
    return 1;
  if (!options.edges.empty() && !saveEdges(options.edges, result))
    return 1;
  if (!options.blocks_colored.empty() &&
      !saveBlocksColored(options.blocks_colored, cloud, result))
    return 1;
  if (!options.mesh.empty() && !saveMesh(options.mesh, result))
    return 1;
  if (!options.normals_colored.empty() &&
      !saveCloud(options.normals_colored, dacpo_tool::normalsColored(output)))
    return 1;

  printStats(result);
  return 0;
}

/* Batch mode, like pcl_normal_estimation: every .pcd/.ply of input_dir (in
 * name order) to the same name in output_dir (created if missing). Goes on
 * after a failed file; 1 if any failed. */
int
orientDirectory(const Options& options)
{
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(options.input_dir, ec)) {
    print_error("Error: -input_dir '%s' is not a directory\n",
                options.input_dir.c_str());
    return 1;
  }
  fs::create_directories(options.output_dir, ec);
  if (ec || !fs::is_directory(options.output_dir)) {
    print_error("Error: cannot create -output_dir '%s': %s\n",
                options.output_dir.c_str(),
                ec.message().c_str());
    return 1;
  }
  std::vector<fs::path> inputs;
  for (const fs::directory_entry& e : fs::directory_iterator(options.input_dir, ec)) {
    const std::string ext = dacpo_tool::extension(e.path().string());
    if (e.is_regular_file() && (ext == ".pcd" || ext == ".ply"))
      inputs.push_back(e.path());
  }
  std::sort(inputs.begin(), inputs.end());
  if (inputs.empty()) {
    print_error("Error: no .pcd or .ply file in '%s'\n", options.input_dir.c_str());
    return 1;
  }
  std::size_t failed = 0;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const fs::path out = fs::path(options.output_dir) / inputs[i].filename();
    info("[%zu/%zu] ", i + 1, inputs.size());
    value("%s\n", inputs[i].filename().string().c_str());
    if (orientFile(inputs[i].string(), out.string(), options) != 0) {
      ++failed;
      print_error("Error: '%s' failed, going on with the next file\n",
                  inputs[i].string().c_str());
    }
  }
  if (failed)
    print_error("Error: %zu of %zu files failed\n", failed, inputs.size());
  return failed ? 1 : 0;
}

int
main(int argc, char** argv)
{
  dacpo_cleanup_install(); /* temporary files go with SIGINT / SIGTERM */
  const bool help = find_switch(argc, argv, "-h") || find_switch(argc, argv, "--help");
  if (argc < 3 || help) {
    print_info("Orient normals with DACPO. For more information, use: %s -h\n",
               argv[0]);
    printHelp(argc, argv);
    return help ? 0 : 1;
  }
  {
    std::string error;
    if (!checkOptions(argc, argv, error)) {
      print_error("Error: %s\n", error.c_str());
      return 1;
    }
  }
  Options options;
  if (!parseOptions(argc, argv, options))
    return 1;
  const std::vector<std::string> files = fileArguments(argc, argv);
  if (options.input_dir.empty() ? files.size() != 2 : !files.empty()) {
    print_error(options.input_dir.empty()
                    ? "Need one input and one output file (.pcd or .ply), got %zu.\n"
                    : "With -input_dir/-output_dir give no file names, got %zu.\n",
                files.size());
    printHelp(argc, argv);
    return 1;
  }
  if (options.quiet) {
    g_verbose = false;
    setVerbosityLevel(L_ERROR);
  }

  if (!options.input_dir.empty())
    return orientDirectory(options);
  return orientFile(files[0], files[1], options);
}
