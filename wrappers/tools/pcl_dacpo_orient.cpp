/* SPDX-License-Identifier: BSD-3-Clause */
/* pcl_dacpo_orient: orient the normals of a .pcd/.ply scan with DACPO.
 * Laid out like PCL's tools/normal_estimation.cpp: printHelp, loadCloud,
 * compute, saveCloud, main. Every input field is kept; normal_x/y/z and
 * curvature are added (or replaced). Diagnostics for tuning: -labels adds the
 * block, component and flip of every point, -edges writes the block-graph edge
 * weights as CSV, -blocks_colored writes one colour per block (darker when the
 * 0-1 program flipped it). A last "stats: ..." line (also with -q) gives the
 * counts, time and peak memory. */
#include <dacpo/dacpo.h>
#include <dacpo/dacpo_param_table.h>

#include <pcl_dacpo/dacpo_normal_orientation.h>

#include <pcl/common/io.h>
#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/console/time.h>
#include <pcl/point_types.h>
#include <pcl/PolygonMesh.h>

#include "dacpo_paths.h"
#include "dacpo_ply.h"
#include "dacpo_tiled.h"
#include "dacpo_tool_io.h"
#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

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

/* Output fields written by -labels; dropped from the input in any case, since
 * labels of an earlier run would be stale. */
const std::vector<std::string> kLabelFields = {"block", "component", "flip"};

/* One command-line option. The help text, the parser and the unknown-option
 * check all read the table below (kOptions), so an option is named once. */
using OptionSpec = dacpo_tool::OptionSpec<Options, dacpo_params>;

using dacpo_tool::setFlag;
using dacpo_tool::setText;
using dacpo_tool::toDouble;
using dacpo_tool::toUnsigned;

/* Setters for fields of dacpo_params, by type. */
template <typename T, T dacpo_params::*Field>
bool
setUnsigned(Options& o, const std::string& s, std::string& error)
{
  std::uint64_t v = 0;
  if (!toUnsigned(s, v) ||
      v > static_cast<std::uint64_t>(std::numeric_limits<T>::max())) {
    error = "expects a non-negative integer, got '" + s + "'";
    return false;
  }
  o.params.*Field = static_cast<T>(v);
  return true;
}

template <double dacpo_params::*Field>
bool
setDouble(Options& o, const std::string& s, std::string& error)
{
  double v = 0.0;
  if (!toDouble(s, v)) {
    error = "expects a number, got '" + s + "'";
    return false;
  }
  o.params.*Field = v;
  return true;
}

template <typename T, T dacpo_params::*Field>
std::string
showNumber(const dacpo_params& d)
{
  std::ostringstream out;
  out << d.*Field;
  return out.str();
}

/* Options generated from the parameter table (dacpo_param_table.h): a VALUE
 * row is "flag X" with the row's doc as its help; SPECIAL rows are written
 * below by hand, NONE rows have no option. */
#define DACPO_CLI_SET_SIZE(name) setUnsigned<size_t, &dacpo_params::name>
#define DACPO_CLI_SET_U64(name) setUnsigned<std::uint64_t, &dacpo_params::name>
#define DACPO_CLI_SET_UINT(name) setUnsigned<unsigned, &dacpo_params::name>
#define DACPO_CLI_SET_INT(name) setUnsigned<int, &dacpo_params::name>
#define DACPO_CLI_SET_FLAG(name) setUnsigned<int, &dacpo_params::name>
#define DACPO_CLI_SET_REAL(name) setDouble<&dacpo_params::name>
#define DACPO_CLI_EXPERT_USER false
#define DACPO_CLI_EXPERT_EXPERT true
#define DACPO_CLI_VALUE(kind, name, who, flag, doc)                                      \
  {flag,                                                                                 \
   "X",                                                                                  \
   doc,                                                                                  \
   showNumber<decltype(dacpo_params::name), &dacpo_params::name>,                        \
   DACPO_CLI_SET_##kind(name),                                                           \
   DACPO_CLI_EXPERT_##who},
#define DACPO_CLI_SPECIAL(kind, name, who, flag, doc)
#define DACPO_CLI_NONE(kind, name, who, flag, doc)

const OptionSpec kOptions[] = {
    /* every VALUE row of the parameter table: "flag X" */
#define DACPO_PARAM(kind, name, def, who, cli, flag, doc) DACPO_CLI_##cli(kind, name, who, flag, doc)
    DACPO_PARAMS()
#undef DACPO_PARAM
    {"-estimate",
     nullptr,
     "estimate PCA normals even if the input has normal_x/y/z\n"
     "(without normals in the input they are always estimated)",
     nullptr,
     setFlag<&Options::estimate>},
    {"-vcr_perspective",
     nullptr,
     "perspective VCR projection (default: orthographic)",
     nullptr,
     [](Options& o, const std::string&, std::string&) {
       o.params.vcr_perspective = 1;
       return true;
     },
     true},
    {"-vcr_c1c2",
     nullptr,
     "VCR score C1*C2 without the boundary factor C_B",
     nullptr,
     [](Options& o, const std::string&, std::string&) {
       o.params.vcr_boundary_factor = 0;
       return true;
     },
     true},
    {"-mesh",
     "F.ply",
     "also write the reconstructed surface (one mesh over\n"
     "all blocks from the final normals, wound like them)",
     nullptr,
     setText<&Options::mesh>},
    {"-memory",
     "X[K|M|G]",
     "out of core: hold at most about X bytes (binary PLY in\n"
     "and .ply out); a larger cloud is oriented in spatial\n"
     "tiles read from disk one at a time, their signs joined\n"
     "where their halos overlap (normals always estimated)",
     nullptr,
     [](Options& o, const std::string& s, std::string& error) {
       double v = 0.0;
       if (!dacpo_tiled_parse_size(s.c_str(), &v)) {
         error = "expects a size such as 4G or 512M, got '" + s + "'";
         return false;
       }
       o.memory = v;
       if (o.memory < 2.0 * DACPO_TILED_BASE_BYTES) {
         error = "needs at least " +
                 std::to_string(static_cast<int>(2.0 * DACPO_TILED_BASE_BYTES / 1048576.0)) +
                 "M, got '" + s + "'";
         return false;
       }
       return true;
     }},
    {"-tiles",
     "P",
     "out of core with tiles of about 0.8 P own points\n"
     "instead of a -memory budget; each tile also reads its\n"
     "halo (16 spacings around it: up to ~3 P in all for\n"
     "small P), reported as largest_tile",
     nullptr,
     [](Options& o, const std::string& s, std::string& error) {
       if (!toUnsigned(s, o.tile_points) || o.tile_points < 16) {
         error = "expects a number of points >= 16, got '" + s + "'";
         return false;
       }
       return true;
     }},
    {"-tile_halo",
     "X",
     "with -memory: how far a tile reads beyond its cell\n"
     "(coordinate units; default: 16 spacings of the cloud)",
     nullptr,
     [](Options& o, const std::string& s, std::string& error) {
       if (!toDouble(s, o.tile_halo) || !(o.tile_halo > 0.0) || !std::isfinite(o.tile_halo)) {
         error = "expects a positive number, got '" + s + "'";
         return false;
       }
       return true;
     }},
    {"-sign",
     "free|keep",
     "global sign: normals face the free space the scan\n"
     "was seen from (free, default; closed objects: outward),\n"
     "or the arbitrary one of the method (keep)",
     nullptr,
     setText<&Options::sign>},
    {"-vp",
     "x,y,z",
     "most normals face this viewpoint (one sign for the whole\n"
     "cloud, consistency is kept)",
     nullptr,
     setText<&Options::viewpoint>},
    {"-separate",
     nullptr,
     "disconnected parts keep the sign they got (undefined relative sign)\n"
     "(default: each part takes the sign that faces the viewpoint\n"
     "implied by the largest part)",
     nullptr,
     [](Options& o, const std::string&, std::string&) {
       o.separate = true;
       return true;
     }},
    {"-bridge",
     nullptr,
     "join disconnected parts along their minimum spanning tree\n"
     "and orient them as one",
     nullptr,
     [](Options& o, const std::string&, std::string&) {
       o.bridge = true;
       return true;
     }},
    {"-scan",
     "auto|single|multi",
     "kind of scan: one depth view (single: layers face one way,\n"
     "no thin part shows two faces) or seen from many places\n"
     "(multi: fused scans, sampled models; the thin-part side cue\n"
     "in every block); auto decides from the sampling density, and\n"
     "leaves the side cue out where the largest plane (a floor)\n"
     "shows offset copies of itself (views fused with a\n"
     "registration error; stats layered=, sides=) (default: auto)",
     nullptr,
     [](Options& o, const std::string& s, std::string& error) {
       if (s == "auto")
         o.params.scan_kind = DACPO_SCAN_AUTO;
       else if (s == "single")
         o.params.scan_kind = DACPO_SCAN_SINGLE_VIEW;
       else if (s == "multi")
         o.params.scan_kind = DACPO_SCAN_MULTI_VIEW;
       else {
         error = "expects auto, single or multi, got '" + s + "'";
         return false;
       }
       return true;
     }},
    {"-no_ipsr",
     nullptr,
     "skip the iterative Poisson refinement",
     nullptr,
     [](Options& o, const std::string&, std::string&) {
       o.params.ipsr_enabled = 0;
       return true;
     },
     true},
    {"-weights",
     "S",
     "block edge weights: vcr | dipole | overlap",
     [](const dacpo_params& d) -> std::string {
       return d.edge_weight == DACPO_WEIGHT_VCR       ? "vcr"
              : d.edge_weight == DACPO_WEIGHT_OVERLAP ? "overlap"
                                                      : "dipole";
     },
     [](Options& o, const std::string& s, std::string& error) {
       if (dacpo_params_set(&o.params, "edge_weight", s.c_str(), nullptr, 0) == DACPO_OK)
         return true;
       error = "must be vcr, dipole or overlap, got '" + s + "'";
       return false;
     },
     true},
    {"-labels",
     nullptr,
     "add int32 fields block, component and flip, and the\n"
     "float field confidence (0..1, how sure the sign is)\n"
     "(flip = 1 if the 0-1 program flipped the block;\n"
     "all -1 for skipped points); then pcl_dacpo_eval\n"
     "splits the error into in-block and block-flip parts",
     nullptr,
     setFlag<&Options::labels>},
    {"-edges",
     "F.csv",
     "write the block-graph edges: block_a,block_b,\n"
     "alpha,alpha_bar,confidence,flipped_a,flipped_b;\n"
     "list the weakest edges (confidence < 0.2)",
     nullptr,
     setText<&Options::edges>},
    {"-blocks_colored",
     "F.{pcd,ply}",
     "PointXYZRGB, one colour per block,\n"
     "darker if flipped, grey if skipped",
     nullptr,
     setText<&Options::blocks_colored>},
    {"-normals_colored",
     "F.{pcd,ply}",
     "PointXYZRGBNormal coloured by\n"
     "the normal's direction, RGB = (n + 1) / 2: a flipped\n"
     "region shows in the complementary colour",
     nullptr,
     setText<&Options::normals_colored>},
    {"-input_dir",
     "D",
     "batch: every .pcd/.ply of D to the same name in -output_dir",
     nullptr,
     setText<&Options::input_dir>},
    {"-output_dir",
     "O",
     "batch: the output folder (created if missing)",
     nullptr,
     setText<&Options::output_dir>},
    {"-q",
     nullptr,
     "quiet: errors and the final stats line only",
     nullptr,
     setFlag<&Options::quiet>},
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
  dacpo_tool::printOptionTable(kOptions, d, 11, 35);
  print_info("  After a successful run the last line on stderr is always\n");
  print_info("  \"stats: points=... blocks=... edges=... ... seconds=... "
             "peak_rss_mb=...\".\n");
  print_info("\nExample:\n  %s scan.ply oriented.pcd -k 10\n", argv[0]);
  print_info("  %s scan.ply oriented.pcd -labels -edges edges.csv "
             "-blocks_colored blocks.pcd\n",
             argv[0]);
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

bool
blockFlipped(const Result& r, std::int32_t block)
{
  return block >= 0 && static_cast<std::size_t>(block) < r.flips.size() &&
         r.flips[block] != 0;
}

/* Writes the block-graph edges as CSV and reports the weakest ones on stderr. */
bool
saveEdges(const std::string& filename, const Result& r)
{
  highlight("Saving ");
  value("%s ", filename.c_str());
  std::ostringstream csv;
  csv << "block_a,block_b,alpha,alpha_bar,confidence,flipped_a,flipped_b\n";
  char row[256];
  for (const dacpo_edge_info& e : r.edges) {
    std::snprintf(row,
                  sizeof(row),
                  "%d,%d,%.9g,%.9g,%.9g,%d,%d\n",
                  static_cast<int>(e.block_a),
                  static_cast<int>(e.block_b),
                  e.alpha,
                  e.alpha_bar,
                  e.confidence,
                  blockFlipped(r, e.block_a) ? 1 : 0,
                  blockFlipped(r, e.block_b) ? 1 : 0);
    csv << row;
  }
  std::string error;
  if (!dacpo_tool::writeAtomically(
          filename,
          [&](const std::string& tmp, std::string& err) {
            return dacpo_tool::writeAllChecked(tmp, csv.str(), err, filename);
          },
          error)) {
    info("\n");
    print_error("Error: %s\n", error.c_str());
    return false;
  }
  info("[done : ");
  value("%zu", r.edges.size());
  info(" edges]\n");

  std::vector<std::size_t> order(r.edges.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return r.edges[a].confidence < r.edges[b].confidence;
  });
  const std::size_t low = static_cast<std::size_t>(
      std::count_if(r.edges.begin(), r.edges.end(), [](const dacpo_edge_info& e) {
        return e.confidence < kLowConfidence;
      }));
  info("Edges with confidence < %g: ", kLowConfidence);
  value("%zu", low);
  info(" of ");
  value("%zu", r.edges.size());
  info("%s\n", order.empty() ? "" : "; the weakest:");
  for (std::size_t i = 0; i < order.size() && i < 10; ++i) {
    const dacpo_edge_info& e = r.edges[order[i]];
    info("  blocks %5d - %-5d alpha ",
         static_cast<int>(e.block_a),
         static_cast<int>(e.block_b));
    value("%-10.4g", e.alpha);
    info(" alpha_bar ");
    value("%-10.4g", e.alpha_bar);
    info(" confidence ");
    value("%-8.4f", e.confidence);
    info(" flipped ");
    value("%d/%d\n",
          blockFlipped(r, e.block_a) ? 1 : 0,
          blockFlipped(r, e.block_b) ? 1 : 0);
  }
  return true;
}

/* Colour of a block: hues 0.618... apart (golden ratio) so neighbouring ids
 * differ; saturation alternates; flipped blocks are darker. */
void
blockColor(std::int32_t block, bool flipped, std::uint8_t rgb[3])
{
  if (block < 0) {
    rgb[0] = rgb[1] = rgb[2] = 128;
    return;
  }
  const double h = std::fmod(0.13 + 0.6180339887498949 * block, 1.0) * 6.0;
  const double s = (block & 1) ? 0.55 : 0.85;
  const double v = flipped ? 0.45 : 0.95;
  /* HSV to RGB: channel n in {5, 3, 1} is v - v s clamp(min(k, 4 - k), 0, 1)
   * with k = (n + h) mod 6. */
  const double n_of[3] = {5.0, 3.0, 1.0};
  for (int ch = 0; ch < 3; ++ch) {
    const double k = std::fmod(n_of[ch] + h, 6.0);
    const double c = v - v * s * std::max(0.0, std::min({k, 4.0 - k, 1.0}));
    rgb[ch] = static_cast<std::uint8_t>(std::lround(255.0 * c));
  }
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
saveBlocksColored(const std::string& filename,
                  const pcl::PCLPointCloud2& input,
                  const Result& r)
{
  const std::size_t n = static_cast<std::size_t>(input.width) * input.height;
  if (r.blocks.size() != n) {
    print_error("Error: the run left no block labels\n");
    return false;
  }
  const pcl::PCLPointCloud2 cloud2 = dacpo_tool::colouredCloud(
      dacpo_tool::readTriplet(input, "x", "y", "z"),
      {},
      [&](std::size_t i, std::uint8_t rgb[3]) {
        blockColor(r.blocks[i], blockFlipped(r, r.blocks[i]), rgb);
      },
      input.is_dense);
  return saveCloud(filename, cloud2);
}

/* Peak resident memory of this process in MiB (Linux: ru_maxrss is in KiB). */
double
peakRssMb()
{
  struct rusage usage;
  if (getrusage(RUSAGE_SELF, &usage) != 0)
    return -1.0;
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

/* The reconstructed surface (-mesh): the scene mesh, wound like the output
 * normals, as binary PLY (vertex x y z, face vertex_indices). */
bool
saveMesh(const std::string& filename, const Result& r)
{
  pcl::PointCloud<pcl::PointXYZ> vertices;
  vertices.resize(r.mesh_vertices.size() / 3);
  for (std::size_t i = 0; i < vertices.size(); ++i)
    vertices[i].getVector3fMap() << r.mesh_vertices[3 * i], r.mesh_vertices[3 * i + 1],
        r.mesh_vertices[3 * i + 2];
  pcl::PolygonMesh mesh;
  pcl::toPCLPointCloud2(vertices, mesh.cloud);
  mesh.polygons.resize(r.mesh_triangles.size() / 3);
  for (std::size_t t = 0; t < mesh.polygons.size(); ++t)
    mesh.polygons[t].vertices = {
        static_cast<pcl::index_t>(r.mesh_triangles[3 * t]),
        static_cast<pcl::index_t>(r.mesh_triangles[3 * t + 1]),
        static_cast<pcl::index_t>(r.mesh_triangles[3 * t + 2])};
  std::string error;
  if (!dacpo_tool::writeAtomically(
          filename,
          [&](const std::string& tmp, std::string& err) {
            /* PCL does not report short writes: read the file back */
            pcl::PolygonMesh back;
            if (pcl::io::savePLYFileBinary(tmp, mesh) < 0 ||
                pcl::io::loadPLYFile(tmp, back) < 0 ||
                back.polygons.size() != mesh.polygons.size() ||
                static_cast<std::size_t>(back.cloud.width) * back.cloud.height !=
                    vertices.size()) {
              err = "cannot write the mesh to '" + filename +
                    "' (short write: disk full or no permission?)";
              return false;
            }
            return true;
          },
          error)) {
    print_error("Error: %s\n", error.c_str());
    return false;
  }
  info("Saved mesh ");
  value("%s", filename.c_str());
  info(": ");
  value("%zu", vertices.size());
  info(" vertices, ");
  value("%zu", mesh.polygons.size());
  info(" triangles\n");
  return true;
}

/* -sign and -vp into the sign policy (and the viewpoint). */
bool
resolveSignPolicy(Options& o)
{
  if (!o.sign.empty()) {
    if (o.sign == "free")
      o.params.sign_policy = DACPO_SIGN_FREE_SPACE;
    else if (o.sign == "keep")
      o.params.sign_policy = DACPO_SIGN_KEEP;
    else {
      print_error(
          "Error: -sign must be free or keep (for a viewpoint use -vp x,y,z), got "
          "'%s'\n",
          o.sign.c_str());
      return false;
    }
  }
  if (o.viewpoint.empty())
    return true;
  double v[3];
  std::stringstream in(o.viewpoint);
  std::string part;
  int got = 0;
  while (got < 4 && std::getline(in, part, ','))
    got += got < 3 && toDouble(part, v[got]) ? 1 : 4;
  if (got != 3) {
    print_error("Error: -vp needs three finite numbers x,y,z\n");
    return false;
  }
  if (o.params.sign_policy == DACPO_SIGN_KEEP) {
    print_error("Error: -vp and -sign keep contradict each other\n");
    return false;
  }
  o.params.sign_policy = DACPO_SIGN_VIEWPOINT;
  for (int k = 0; k < 3; ++k)
    o.params.viewpoint[k] = v[k];
  return true;
}

/* -mesh, the batch folders and the side outputs: extensions and combinations. */
bool
checkFileOptions(Options& o)
{
  if (!o.mesh.empty()) {
    if (dacpo_tool::extension(o.mesh) != ".ply") {
      print_error("Error: -mesh needs a .ply file name, got '%s'\n", o.mesh.c_str());
      return false;
    }
    o.params.keep_mesh = 1;
  }
  if (o.input_dir.empty() != o.output_dir.empty()) {
    print_error("Error: -input_dir and -output_dir go together\n");
    return false;
  }
  if (!o.input_dir.empty() && (!o.edges.empty() || !o.blocks_colored.empty() ||
                               !o.mesh.empty() || !o.normals_colored.empty())) {
    print_error(
        "Error: -edges, -blocks_colored, -mesh and -normals_colored name one file: "
        "not with -input_dir\n");
    return false;
  }
  for (const std::string* side : {&o.blocks_colored, &o.normals_colored}) {
    const std::string ext = dacpo_tool::extension(*side);
    if (!side->empty() && ext != ".pcd" && ext != ".ply") {
      print_error("Error: %s needs a .pcd or .ply file name, got '%s'\n",
                  side == &o.blocks_colored ? "-blocks_colored" : "-normals_colored",
                  side->c_str());
      return false;
    }
  }
  return true;
}

bool
parseOptions(int argc, char** argv, Options& o)
{
  dacpo_params_init(&o.params);
  if (!dacpo_tool::applyOptions(kOptions, argc, argv, o) || !resolveSignPolicy(o))
    return false;
  if (o.separate)
    o.params.disconnected = DACPO_DISCONNECTED_SEPARATE;
  if (o.bridge)
    o.params.disconnected = DACPO_DISCONNECTED_BRIDGE;
  if (!checkFileOptions(o))
    return false;
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

/* One machine-readable line, printed even with -q (benchmarks grep it). */
void
printStats(const Result& result)
{
  const dacpo_stats& s = result.stats;
  const std::size_t low = static_cast<std::size_t>(std::count_if(
      result.edges.begin(), result.edges.end(), [](const dacpo_edge_info& e) {
        return e.confidence < kLowConfidence;
      }));
  std::fprintf(stderr,
               "stats: points=%zu blocks=%zu edges=%zu low_conf_edges=%zu "
               "components=%zu parts=%zu parts_related=%zu view_score=%.3f flipped=%zu "
               "cue_anchored=%zu parts_cue_signed=%zu cue_reconciled=%zu surface_turned=%zu scan=%s single_view_fit=%.3f c=%g "
               "layers=%g two_sheet=%g layered=%.3f copies=%.3f sides=%g "
               "sign_flipped=%d sign_facing=%.3f sign_enclosed=%d solver_optimal=%d "
               "ipsr_iterations_mean=%.2f "
               "ipsr_iterations_max=%zu seconds=%.3f peak_rss_mb=%.1f\n",
               result.points,
               s.num_blocks,
               s.num_block_edges,
               low,
               s.num_components,
               s.num_parts,
               s.parts_related,
               s.view_score,
               s.flipped_blocks,
               s.cue_anchored_blocks,
               s.parts_cue_signed,
               s.cue_reconciled_blocks,
               s.surface_vote_turned,
               s.scan_kind == DACPO_SCAN_SINGLE_VIEW ? "single" : "multi",
               s.single_view_fit,
               s.dipole_c_used,
               s.dipole_layers_used,
               s.dipole_two_sheet_used,
               s.layered_share,
               s.layered_copies,
               s.dipole_sides_used,
               s.sign_flipped,
               s.sign_facing,
               s.sign_enclosed,
               s.solver_optimal ? 1 : 0,
               s.num_blocks ? static_cast<double>(s.ipsr_iterations_total) /
                                  static_cast<double>(s.num_blocks)
                            : 0.0,
               s.ipsr_iterations_max,
               s.total_seconds,
               peakRssMb());
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
    if (!dacpo_tool::checkOptionTable(kOptions, argc, argv, error)) {
      print_error("Error: %s\n", error.c_str());
      return 1;
    }
  }
  Options options;
  if (!parseOptions(argc, argv, options))
    return 1;
  const std::vector<std::string> files =
      dacpo_tool::fileArguments(argc, argv, dacpo_tool::optionNames(kOptions, true));
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
