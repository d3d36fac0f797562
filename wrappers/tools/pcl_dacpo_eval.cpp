/* SPDX-License-Identifier: BSD-3-Clause */
/* pcl_dacpo_eval: the paper's orientation metric (§6). Share of points whose
 * predicted normal makes more than 90 degrees with the ground truth, after one
 * global flip when that lowers it (so at most 50 %), over all points and over
 * the largest connected component of the k = 10 nearest-neighbour graph only
 * (exact duplicates merged, graph symmetrized: the core's definition). A
 * predicted normal that is not finite, or exactly perpendicular, is wrong under
 * either sign (dacpo_score_oriented() in wrappers/support).
 *
 * When the prediction carries pcl_dacpo_orient -labels fields (block, and
 * component), the error is split by where it comes from: inside the blocks
 * (stages 2 and 3: wrong even with the best sign per block) or from block
 * flips (edge weights and the 0-1 program: blocks whose majority is wrong under
 * the best sign of their component). */
#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include "dacpo_paths.h"
#include "dacpo_scene.h"
#include "dacpo_tool_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

using namespace pcl::console;

namespace {

constexpr std::size_t kGraphK = 10;

/* The command line of the tool. */
struct EvalOptions {
  std::vector<std::string> files; /* ground truth, prediction */
  std::string colored, normals_colored;
  bool json = false;
};

/* One command-line option. The help text, the parser and the unknown-option
 * check all read the table below (kEvalOptions), so an option is named once;
 * file names are checked in parseEvalOptions(). */
using EvalOptionSpec = dacpo_tool::OptionSpec<EvalOptions, EvalOptions>;

const EvalOptionSpec kEvalOptions[] = {
    {"-normals_colored",
     "F.{pcd,ply}",
     "the predicted cloud coloured by\n"
     "normal direction, RGB = (n + 1) / 2",
     nullptr,
     dacpo_tool::setText<&EvalOptions::normals_colored>},
    {"-colored",
     "out.pcd",
     "write the points coloured blue (correct)\n"
     "  or red (wrong) with the predicted normals",
     nullptr,
     dacpo_tool::setText<&EvalOptions::colored>},
    {"-json",
     nullptr,
     "print one line of JSON on stdout:",
     nullptr,
     dacpo_tool::setFlag<&EvalOptions::json>},
};

void
printHelp(int, char** argv)
{
  print_error("Syntax is: %s ground_truth.{ply,pcd} predicted.{pcd,ply} <options>\n",
              argv[0]);
  print_info(
      "  Percentage of points whose normal is more than 90 degrees from the ground\n");
  print_info(
      "  truth after one global flip (paper metric), over all points and over the\n");
  print_info(
      "  largest connected component of the k = 10 neighbour graph. Both files must\n");
  print_info(
      "  hold the same points in the same order; NaN predicted normals are wrong.\n");
  print_info("  where options are:\n");
  dacpo_tool::printOptionTable(kEvalOptions, EvalOptions(), 16, 38);
  print_info("  {\"file\":..., \"points\":N, \"wrong_pct\":x, "
             "\"largest_component_points\":M,\n");
  print_info("   \"largest_component_wrong_pct\":y, \"components\":C,\n");
  print_info("   \"right_sign_pct\": %% right as given, without the global flip}\n");
  print_info(
      "  If the prediction has a 'block' field (pcl_dacpo_orient -labels), also:\n");
  print_info("   \"blocks\":B, \"component_wrong_pct\": with the best sign per "
             "component,\n");
  print_info("   \"intra_block_wrong_pct\": with the best sign per block (stage 2+3 "
             "error),\n");
  print_info("   \"flip_wrong_blocks\": blocks whose majority is wrong under their "
             "component's\n");
  print_info("   best sign, \"flip_wrong_points_pct\": %% of all points in them (stage "
             "4+5 error),\n");
  print_info("   \"largest_block_wrong\": the 5 blocks with most wrong points under "
             "that sign,\n");
  print_info("   [{\"id\":b, \"component\":c, \"points\":p, \"wrong_pct\":w}, "
             "...]. Components come\n");
  print_info("   from the 'component' field if present, else from the graph above.\n");
}

/* Where the wrong points are, given block labels (pcl_dacpo_orient -labels). */
struct BlockReport {
  std::size_t blocks = 0;
  double component_wrong_pct = 0.0;
  double intra_block_wrong_pct = 0.0;
  std::size_t flip_wrong_blocks = 0;
  double flip_wrong_points_pct = 0.0;
  struct Worst {
    std::int32_t id, component;
    std::size_t points;
    double wrong_pct;
  };
  std::vector<Worst> worst; /* up to 5, most wrong points first */
};

/* Same three states as the metric: 0 right as is, 1 right when flipped,
 * 2 wrong either way (not finite or perpendicular). */
unsigned
scoreState(const float* gt, const float* pred, std::size_t i)
{
  const double d = static_cast<double>(gt[3 * i]) * pred[3 * i] +
                   static_cast<double>(gt[3 * i + 1]) * pred[3 * i + 1] +
                   static_cast<double>(gt[3 * i + 2]) * pred[3 * i + 2];
  return d > 0.0 ? 0u : (d < 0.0 ? 1u : 2u);
}

/* Dense 0..max relabelling of the non-negative labels; negative stays -1. */
std::size_t
denseLabels(const std::vector<std::int32_t>& in,
            std::vector<std::int32_t>& out,
            std::vector<std::int32_t>& original)
{
  std::vector<std::int32_t> sorted;
  for (std::int32_t v : in)
    if (v >= 0)
      sorted.push_back(v);
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  out.resize(in.size());
  for (std::size_t i = 0; i < in.size(); ++i)
    out[i] = in[i] < 0 ? -1
                       : static_cast<std::int32_t>(
                             std::lower_bound(sorted.begin(), sorted.end(), in[i]) -
                             sorted.begin());
  original = sorted;
  return sorted.size();
}

/* Points without a block (label < 0) count as wrong only when wrong under both
 * signs, so intra_block_wrong_pct <= component_wrong_pct <= wrong_pct. */
BlockReport
blockReport(const std::vector<float>& gt,
            const std::vector<float>& pred,
            const std::vector<std::int32_t>& block_in,
            const std::vector<std::int32_t>& component_in)
{
  const std::size_t n = block_in.size();
  std::vector<std::int32_t> block, comp, block_id, comp_id;
  const std::size_t nb = denseLabels(block_in, block, block_id);
  const std::size_t nc = denseLabels(component_in, comp, comp_id);
  std::vector<unsigned> state(n);
  for (std::size_t i = 0; i < n; ++i)
    state[i] = scoreState(gt.data(), pred.data(), i);

  /* Best sign per component (0: as is, 1: flipped). */
  std::vector<std::size_t> ccount(3 * nc, 0);
  std::size_t unlabelled_wrong = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (comp[i] >= 0)
      ++ccount[3 * comp[i] + state[i]];
  std::vector<unsigned> csign(nc);
  std::size_t comp_wrong = 0;
  for (std::size_t c = 0; c < nc; ++c) {
    /* Flip when more points are right flipped than as they are. */
    csign[c] = ccount[3 * c] < ccount[3 * c + 1] ? 1u : 0u;
    comp_wrong += std::min(ccount[3 * c], ccount[3 * c + 1]) + ccount[3 * c + 2];
  }

  /* Per block: points, wrong under its best sign, wrong under the signs of the
   * points' components. */
  std::vector<std::size_t> bcount(3 * nb, 0), bwrong(nb, 0);
  std::vector<std::int32_t> bcomp(nb, -1);
  for (std::size_t i = 0; i < n; ++i) {
    const bool wrong_c =
        comp[i] < 0 ? state[i] == 2 : (state[i] == 2 || state[i] != csign[comp[i]]);
    if (comp[i] < 0)
      comp_wrong += wrong_c;
    if (block[i] < 0) {
      unlabelled_wrong += state[i] == 2;
      continue;
    }
    ++bcount[3 * block[i] + state[i]];
    bwrong[block[i]] += wrong_c;
    if (bcomp[block[i]] < 0 && comp[i] >= 0)
      bcomp[block[i]] = comp_id[comp[i]];
  }
  BlockReport r;
  r.blocks = nb;
  std::size_t intra_wrong = unlabelled_wrong, flip_points = 0;
  std::vector<std::size_t> order(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    const std::size_t* c = &bcount[3 * b];
    const std::size_t points = c[0] + c[1] + c[2];
    intra_wrong += std::min(c[0], c[1]) + c[2];
    if (2 * bwrong[b] > points) {
      ++r.flip_wrong_blocks;
      flip_points += points;
    }
    order[b] = b;
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return bwrong[a] > bwrong[b];
  });
  for (std::size_t k = 0; k < order.size() && k < 5; ++k) {
    const std::size_t b = order[k];
    const std::size_t points = bcount[3 * b] + bcount[3 * b + 1] + bcount[3 * b + 2];
    r.worst.push_back({block_id[b],
                       bcomp[b],
                       points,
                       points ? 100.0 * static_cast<double>(bwrong[b]) / points : 0.0});
  }
  const double scale = n ? 100.0 / static_cast<double>(n) : 0.0;
  r.component_wrong_pct = scale * static_cast<double>(comp_wrong);
  r.intra_block_wrong_pct = scale * static_cast<double>(intra_wrong);
  r.flip_wrong_points_pct = scale * static_cast<double>(flip_points);
  return r;
}

/* Disjoint sets with path halving and union by size. */
struct DisjointSets {
  std::vector<std::int32_t> parent, size;
  explicit DisjointSets(std::size_t n)
      : parent(n)
      , size(n, 1)
  {
    std::iota(parent.begin(), parent.end(), 0);
  }
  std::int32_t
  find(std::int32_t a)
  {
    while (parent[a] != a) {
      parent[a] = parent[parent[a]];
      a = parent[a];
    }
    return a;
  }
  void
  unite(std::int32_t a, std::int32_t b)
  {
    a = find(a);
    b = find(b);
    if (a == b)
      return;
    if (size[a] < size[b])
      std::swap(a, b);
    parent[b] = a;
    size[a] += size[b];
  }
};

/* Component label of every point (numbered by first point), as the core defines
 * them: exact duplicates merged, k nearest distinct neighbours, i ~ j if either
 * lists the other. Returns the number of components. */
std::size_t
componentLabels(const std::vector<float>& xyz, std::vector<std::int32_t>& label)
{
  const std::size_t n = xyz.size() / 3;
  /* Merge exact duplicates (-0 == +0 because the comparison is on values). */
  std::vector<std::int32_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  auto less = [&](std::int32_t a, std::int32_t b) {
    for (int d = 0; d < 3; ++d)
      if (xyz[3 * a + d] != xyz[3 * b + d])
        return xyz[3 * a + d] < xyz[3 * b + d];
    return false;
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::int32_t> distinct_of(n);
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (std::size_t r = 0; r < n; ++r) {
    const std::int32_t i = order[r];
    if (r == 0 || less(order[r - 1], i))
      cloud->push_back(pcl::PointXYZ(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]));
    distinct_of[i] = static_cast<std::int32_t>(cloud->size() - 1);
  }
  const std::size_t m = cloud->size();
  DisjointSets sets(m);
  if (m > 1) {
    const int k = static_cast<int>(std::min(kGraphK, m - 1));
    pcl::search::KdTree<pcl::PointXYZ> tree;
    tree.setInputCloud(cloud);
    pcl::Indices nn;
    std::vector<float> nd;
    for (std::size_t i = 0; i < m; ++i) {
      /* k + 1: the query itself comes back (distinct points, so only once). */
      tree.nearestKSearch((*cloud)[i], k + 1, nn, nd);
      int taken = 0;
      for (std::size_t j = 0; j < nn.size() && taken < k; ++j) {
        if (nn[j] == static_cast<pcl::index_t>(i))
          continue;
        sets.unite(static_cast<std::int32_t>(i), nn[j]);
        ++taken;
      }
    }
  }
  std::vector<std::int32_t> root_label(m, -1);
  label.assign(n, -1);
  std::size_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t r = sets.find(distinct_of[i]);
    if (root_label[r] < 0)
      root_label[r] = static_cast<std::int32_t>(count++);
    label[i] = root_label[r];
  }
  return count;
}

std::string
jsonString(const std::string& s)
{
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    }
    else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\u%04x", c);
      out += buf;
    }
    else
      out += static_cast<char>(c);
  }
  return out + "\"";
}

bool
saveColored(const std::string& path,
            const std::vector<float>& xyz,
            const std::vector<float>& normals,
            const std::vector<bool>& wrong)
{
  const pcl::PCLPointCloud2 cloud = dacpo_tool::colouredCloud(
      xyz,
      normals,
      [&](std::size_t i, std::uint8_t rgb[3]) {
        rgb[0] = wrong[i] ? 255 : 0; /* red = wrong, blue = right */
        rgb[2] = wrong[i] ? 0 : 255;
      },
      false);
  std::string error;
  if (!dacpo_tool::saveCloud2(path, cloud, error)) {
    print_error("Error: %s\n", error.c_str());
    return false;
  }
  return true;
}

/* Reads and checks the command line; false: exit with *exit_code (help, or a
 * message was printed). */
bool
parseEvalOptions(int argc, char** argv, EvalOptions& o, int& exit_code)
{
  const bool help = find_switch(argc, argv, "-h") || find_switch(argc, argv, "--help");
  exit_code = 1;
  if (argc < 3 || help) {
    printHelp(argc, argv);
    exit_code = help ? 0 : 1;
    return false;
  }
  std::string error;
  if (!dacpo_tool::checkOptionTable(kEvalOptions, argc, argv, error)) {
    print_error("Error: %s\n", error.c_str());
    return false;
  }
  o.files = dacpo_tool::fileArguments(
      argc, argv, dacpo_tool::optionNames(kEvalOptions, true));
  if (o.files.size() != 2) {
    print_error("Need a ground-truth and a predicted file (.pcd or .ply), got %zu.\n",
                o.files.size());
    printHelp(argc, argv);
    return false;
  }
  /* in command-line order; an option missing its value is an error */
  if (!dacpo_tool::applyOptions(kEvalOptions, argc, argv, o))
    return false;
  if (!o.normals_colored.empty() &&
      dacpo_tool::extension(o.normals_colored) != ".pcd" &&
      dacpo_tool::extension(o.normals_colored) != ".ply") {
    print_error("Error: -normals_colored needs a .pcd or .ply file name, got '%s'\n",
                o.normals_colored.c_str());
    return false;
  }
  if (!o.colored.empty() && dacpo_tool::extension(o.colored) != ".pcd") {
    print_error("Error: -colored needs a .pcd file name, got '%s'\n",
                o.colored.c_str());
    return false;
  }
  /* a folder that does not exist is said now, not after the scoring */
  for (const std::string* path : {&o.colored, &o.normals_colored}) {
    char err[512];
    if (!path->empty() && dacpo_output_path_check(path->c_str(), err, sizeof(err)) != 0) {
      print_error("Error: %s\n", err);
      return false;
    }
  }
  return true;
}

/* Loads both files: each with normals, the same number of points, not none. */
bool
loadPair(const std::vector<std::string>& files,
         pcl::PCLPointCloud2& gt2,
         pcl::PCLPointCloud2& pred2,
         std::size_t& n)
{
  std::string error;
  for (int f = 0; f < 2; ++f) {
    pcl::PCLPointCloud2& c = f == 0 ? gt2 : pred2;
    if (!dacpo_tool::loadCloud2(files[f], c, error)) {
      print_error("Error: %s\n", error.c_str());
      return false;
    }
    if (!dacpo_tool::hasFields(c, {"normal_x", "normal_y", "normal_z"})) {
      print_error("Error: '%s' has no normals (normal_x/y/z or nx/ny/nz)\n",
                  files[f].c_str());
      return false;
    }
  }
  n = static_cast<std::size_t>(gt2.width) * gt2.height;
  const std::size_t n_pred = static_cast<std::size_t>(pred2.width) * pred2.height;
  if (n != n_pred) {
    print_error("Error: point counts differ: %zu in '%s', %zu in '%s'\n",
                n,
                files[0].c_str(),
                n_pred,
                files[1].c_str());
    return false;
  }
  if (n == 0) {
    print_error("Error: '%s' has no points\n", files[0].c_str());
    return false;
  }
  return true;
}

/* Every ground-truth point finite with a finite non-zero normal. */
bool
checkGroundTruth(const std::vector<float>& xyz, const std::vector<float>& gt)
{
  for (std::size_t i = 0; 3 * i < xyz.size(); ++i) {
    const float* p = &xyz[3 * i];
    const float* g = &gt[3 * i];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]) ||
        !std::isfinite(g[0]) || !std::isfinite(g[1]) || !std::isfinite(g[2]) ||
        (g[0] == 0.0f && g[1] == 0.0f && g[2] == 0.0f)) {
      print_error("Error: ground-truth point %zu has a non-finite coordinate or a "
                  "non-finite/zero normal\n",
                  i);
      return false;
    }
  }
  return true;
}

/* The ground truth's points in a local frame (for the float k-NN search of the
 * components); warns when the prediction's points are elsewhere. */
std::vector<float>
localPoints(const pcl::PCLPointCloud2& gt2, const pcl::PCLPointCloud2& pred2)
{
  /* Same order? A reordered prediction would give a meaningless score. In
   * double: georeferenced files differ in float by the grid of their offset. */
  const std::vector<double> xyzd = dacpo_tool::readTriplet<double>(gt2, "x", "y", "z");
  const std::vector<double> pxyz =
      dacpo_tool::readTriplet<double>(pred2, "x", "y", "z");
  double max_offset = 0.0, extent = 0.0;
  for (std::size_t i = 0; i < xyzd.size(); ++i) {
    if (std::isfinite(pxyz[i]))
      max_offset = std::max(max_offset, std::fabs(pxyz[i] - xyzd[i]));
    extent = std::max(extent, std::fabs(xyzd[i]));
  }
  const dacpo_tool::LocalFrame frame = dacpo_tool::localFrame(xyzd);
  std::vector<float> local(xyzd.size());
  for (std::size_t i = 0; i < xyzd.size(); ++i)
    local[i] = static_cast<float>((xyzd[i] - frame.centre[i % 3]) / frame.scale);
  if (max_offset > 1e-4 * std::max(1.0, extent))
    print_warn(stderr,
               "Warning: predicted positions differ from the ground truth by up to "
               "%g: are the points in the same order?\n",
               max_offset);
  return local;
}

/* What the tool reports. */
struct EvalScores {
  std::size_t points = 0;
  double pct_all = 0.0;
  std::size_t wrong_all = 0;
  std::size_t components = 0;
  std::size_t largest_points = 0;
  double pct_largest = 0.0;
  double facing_pct = 0.0; /* right with the sign as given */
  bool has_confidence = false;
  double wrong_in_low10 = 0.0, low10_wrong = 0.0;
  bool has_blocks = false;
  BlockReport br;
};

/* The paper metric over the largest component of label (of s.components). */
double
largestComponentScore(const std::vector<float>& gt,
                      const std::vector<float>& pred,
                      const std::vector<std::int32_t>& label,
                      EvalScores& s)
{
  std::vector<std::size_t> sizes(s.components, 0);
  for (std::int32_t l : label)
    ++sizes[l];
  const std::int32_t largest = static_cast<std::int32_t>(
      std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
  s.largest_points = sizes[largest];
  std::vector<float> gt_l, pred_l;
  gt_l.reserve(3 * sizes[largest]);
  pred_l.reserve(3 * sizes[largest]);
  for (std::size_t i = 0; i < label.size(); ++i)
    if (label[i] == largest) {
      gt_l.insert(gt_l.end(), &gt[3 * i], &gt[3 * i + 3]);
      pred_l.insert(pred_l.end(), &pred[3 * i], &pred[3 * i + 3]);
    }
  return dacpo_score_oriented(
      gt_l.data(), pred_l.data(), sizes[largest], nullptr, nullptr);
}

/* Per point under the global sign chosen for the all-points score into wrong;
 * returns the % right without that choice (the sign the user gets). */
double
wrongPoints(const std::vector<float>& gt,
            const std::vector<float>& pred,
            std::size_t n,
            std::vector<bool>& wrong)
{
  wrong.assign(n, false);
  std::size_t wrong_pos = 0, wrong_neg = 0;
  std::vector<double> dot(n);
  for (std::size_t i = 0; i < n; ++i) {
    dot[i] = static_cast<double>(gt[3 * i]) * pred[3 * i] +
             static_cast<double>(gt[3 * i + 1]) * pred[3 * i + 1] +
             static_cast<double>(gt[3 * i + 2]) * pred[3 * i + 2];
    wrong_pos += !(dot[i] > 0.0);
    wrong_neg += !(dot[i] < 0.0);
  }
  const bool flip = wrong_neg < wrong_pos;
  for (std::size_t i = 0; i < n; ++i)
    wrong[i] = flip ? !(dot[i] < 0.0) : !(dot[i] > 0.0);
  return n ? 100.0 * static_cast<double>(n - wrong_pos) / static_cast<double>(n) : 0.0;
}

/* With a confidence field: which share of the wrong points the least
 * confident 10 % of the points hold (10 % if confidence says nothing). */
void
confidenceShares(const pcl::PCLPointCloud2& pred2,
                 const std::vector<bool>& wrong,
                 EvalScores& s)
{
  const std::size_t n = wrong.size();
  const std::vector<float> conf = dacpo_tool::readFloatField(pred2, "confidence");
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  /* NaN (skipped points) last; ties keep the point order */
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const float x = std::isnan(conf[a]) ? 2.0f : conf[a];
    const float y = std::isnan(conf[b]) ? 2.0f : conf[b];
    return x < y;
  });
  const std::size_t low = (n + 9) / 10;
  std::size_t wrong_total = 0, wrong_low = 0;
  for (std::size_t k = 0; k < n; ++k) {
    wrong_total += wrong[order[k]];
    if (k < low)
      wrong_low += wrong[order[k]];
  }
  s.wrong_in_low10 = wrong_total ? 100.0 * wrong_low / wrong_total : 0.0;
  s.low10_wrong = low ? 100.0 * wrong_low / low : 0.0;
}

/* -normals_colored and -colored. */
bool
saveSideOutputs(const EvalOptions& o,
                const pcl::PCLPointCloud2& pred2,
                const std::vector<float>& xyz,
                const std::vector<float>& pred,
                const std::vector<bool>& wrong)
{
  if (!o.normals_colored.empty()) {
    std::string error;
    if (!dacpo_tool::saveCloud2(
            o.normals_colored, dacpo_tool::normalsColored(pred2), error)) {
      print_error("Error: %s\n", error.c_str());
      return false;
    }
  }
  if (!o.colored.empty()) {
    if (!saveColored(o.colored, xyz, pred, wrong)) {
      print_error("Error: cannot write '%s'\n", o.colored.c_str());
      return false;
    }
  }
  return true;
}

/* The -json line. */
void
printJson(const std::string& file, const EvalScores& s)
{
  std::printf("{\"file\":%s, \"points\":%zu, \"wrong_pct\":%.4f, "
              "\"largest_component_points\":%zu, \"largest_component_wrong_pct\":%.4f, "
              "\"components\":%zu, \"right_sign_pct\":%.4f",
              jsonString(file).c_str(),
              s.points,
              s.pct_all,
              s.largest_points,
              s.pct_largest,
              s.components,
              s.facing_pct);
  if (s.has_confidence)
    std::printf(", \"wrong_in_least_confident10_pct\":%.4f, "
                "\"least_confident10_wrong_pct\":%.4f",
                s.wrong_in_low10,
                s.low10_wrong);
  if (s.has_blocks) {
    const BlockReport& br = s.br;
    std::printf(", \"blocks\":%zu, \"component_wrong_pct\":%.4f, "
                "\"intra_block_wrong_pct\":%.4f, \"flip_wrong_blocks\":%zu, "
                "\"flip_wrong_points_pct\":%.4f, \"largest_block_wrong\":[",
                br.blocks,
                br.component_wrong_pct,
                br.intra_block_wrong_pct,
                br.flip_wrong_blocks,
                br.flip_wrong_points_pct);
    for (std::size_t k = 0; k < br.worst.size(); ++k)
      std::printf("%s{\"id\":%d, \"component\":%d, \"points\":%zu, "
                  "\"wrong_pct\":%.2f}",
                  k ? ", " : "",
                  static_cast<int>(br.worst[k].id),
                  static_cast<int>(br.worst[k].component),
                  br.worst[k].points,
                  br.worst[k].wrong_pct);
    std::printf("]");
  }
  std::printf("}\n");
}

/* The in-block / block-flip split of the text report. */
void
printBlockText(const BlockReport& br)
{
  print_info("  %zu blocks. Wrong with the best sign per component: ", br.blocks);
  print_value("%.2f%%", br.component_wrong_pct);
  print_info("; per block (in-block error, stages 2-3): ");
  print_value("%.2f%%\n", br.intra_block_wrong_pct);
  print_info("  Blocks flipped wrong (stages 4-5): ");
  print_value("%zu", br.flip_wrong_blocks);
  print_info(" of ");
  print_value("%zu", br.blocks);
  print_info(", holding ");
  print_value("%.2f%%", br.flip_wrong_points_pct);
  print_info(" of the points\n");
  if (!br.worst.empty())
    print_info("  Blocks with most wrong points:\n");
  for (const BlockReport::Worst& w : br.worst) {
    print_info("    block %5d (component %d): ",
               static_cast<int>(w.id),
               static_cast<int>(w.component));
    print_value("%zu", w.points);
    print_info(" points, ");
    print_value("%.2f%%", w.wrong_pct);
    print_info(" wrong\n");
  }
}

/* The human-readable report. */
void
printText(const std::string& file, const EvalScores& s)
{
  print_info("%s: ", file.c_str());
  print_value("%.2f%%", s.pct_all);
  print_info(" of ");
  print_value("%zu", s.points);
  print_info(" points wrong (");
  print_value("%zu", s.wrong_all);
  print_info("); largest of ");
  print_value("%zu", s.components);
  print_info(" component(s): ");
  print_value("%.2f%%", s.pct_largest);
  print_info(" of ");
  print_value("%zu", s.largest_points);
  print_info(" points; with the sign as given (no global flip): ");
  print_value("%.2f%%", s.facing_pct);
  print_info(" right\n");
  if (s.has_confidence) {
    print_info("  The least confident 10%% of the points hold ");
    print_value("%.1f%%", s.wrong_in_low10);
    print_info(" of the wrong ones (");
    print_value("%.1f%%", s.low10_wrong);
    print_info(" of them are wrong)\n");
  }
  if (s.has_blocks)
    printBlockText(s.br);
}

} // namespace

int
main(int argc, char** argv)
{
  dacpo_cleanup_install(); /* temporary files go with SIGINT / SIGTERM */
  EvalOptions options;
  int exit_code = 1;
  if (!parseEvalOptions(argc, argv, options, exit_code))
    return exit_code;
  const std::vector<std::string>& files = options.files;

  pcl::PCLPointCloud2 gt2, pred2;
  EvalScores s;
  if (!loadPair(files, gt2, pred2, s.points))
    return 1;
  const std::size_t n = s.points;
  const std::vector<float> xyz = dacpo_tool::readTriplet(gt2, "x", "y", "z");
  const std::vector<float> gt =
      dacpo_tool::readTriplet(gt2, "normal_x", "normal_y", "normal_z");
  const std::vector<float> pred =
      dacpo_tool::readTriplet(pred2, "normal_x", "normal_y", "normal_z");
  if (!checkGroundTruth(xyz, gt))
    return 1;
  const std::vector<float> local = localPoints(gt2, pred2);

  s.pct_all = dacpo_score_oriented(gt.data(), pred.data(), n, nullptr, &s.wrong_all);
  std::vector<std::int32_t> label;
  s.components = componentLabels(local, label);
  s.pct_largest = largestComponentScore(gt, pred, label, s);
  if (s.pct_all < 0.0 || s.pct_largest < 0.0) {
    print_error("Error: scoring failed (out of memory)\n");
    return 1;
  }
  std::vector<bool> wrong;
  s.facing_pct = wrongPoints(gt, pred, n, wrong);
  s.has_confidence = dacpo_tool::hasFields(pred2, {"confidence"});
  if (s.has_confidence)
    confidenceShares(pred2, wrong, s);
  if (!saveSideOutputs(options, pred2, xyz, pred, wrong))
    return 1;

  s.has_blocks = dacpo_tool::hasFields(pred2, {"block"});
  if (s.has_blocks)
    s.br = blockReport(gt,
                       pred,
                       dacpo_tool::readInt32Field(pred2, "block"),
                       dacpo_tool::hasFields(pred2, {"component"})
                           ? dacpo_tool::readInt32Field(pred2, "component")
                           : label);
  if (options.json)
    printJson(files[1], s);
  else
    printText(files[1], s);
  return 0;
}
