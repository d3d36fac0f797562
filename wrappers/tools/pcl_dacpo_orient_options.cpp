/* SPDX-License-Identifier: BSD-3-Clause */
/* pcl_dacpo_orient's command line: one table (kOptions) gives the help text,
 * the parser and the unknown-option check, so an option is named once; the
 * value options of the method come from the parameter table
 * (dacpo_param_table.h). Then the checks that combine options. */
#include "pcl_dacpo_orient.h"

#include <dacpo/dacpo_param_table.h>

#include "dacpo_tiled.h"
#include "dacpo_tool_io.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

using namespace pcl::console;

namespace orient_tool {
namespace {

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
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc) DACPO_CLI_##cli(kind, name, who, flag, doc)
    DACPO_PARAMS()
#undef DACPO_PARAM
    {"-estimate",
     nullptr,
     "estimate PCA normals even if the input has normal_x/y/z\n"
     "(without normals in the input they are always estimated)",
     nullptr,
     setFlag<&Options::estimate>},
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

} // namespace

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

bool
checkOptions(int argc, char** argv, std::string& error)
{
  return dacpo_tool::checkOptionTable(kOptions, argc, argv, error);
}

std::vector<std::string>
fileArguments(int argc, char** argv)
{
  return dacpo_tool::fileArguments(argc, argv, dacpo_tool::optionNames(kOptions, true));
}

} // namespace orient_tool
