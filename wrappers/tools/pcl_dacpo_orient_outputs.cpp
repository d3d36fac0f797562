/* SPDX-License-Identifier: BSD-3-Clause */
/* pcl_dacpo_orient's writers: the output cloud, the diagnostics a run leaves
 * (-edges CSV with the weakest edges listed, -blocks_colored, -mesh) and the
 * machine-readable stats line. Every file is written atomically (a temporary
 * renamed into place) and checked, so a full disk is an error, not a stub. */
#include "pcl_dacpo_orient.h"

#include <pcl/PolygonMesh.h>
#include <pcl/common/io.h>
#include <pcl/console/time.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include "dacpo_tool_io.h"
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

using namespace pcl::console;

namespace orient_tool {
namespace {

bool
blockFlipped(const Result& r, std::int32_t block)
{
  return block >= 0 && static_cast<std::size_t>(block) < r.flips.size() &&
         r.flips[block] != 0;
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

} // namespace

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
               "cue_anchored=%zu parts_cue_signed=%zu cue_reconciled=%zu "
               "surface_turned=%zu sensor_turned=%zu frame_sensors=%zu "
               "frame_turned=%zu scan=%s single_view_fit=%.3f c=%g "
               "layers=%g two_sheet=%g layered=%.3f copies=%.3f doubled=%.3f "
               "crossing=%.3f "
               "copy_axes=%zu sides=%g "
               "sign_flipped=%d sign_facing=%.3f sign_enclosed=%d solver_optimal=%d "
               "ipsr_iterations_mean=%.2f "
               "ipsr_iterations_max=%zu restarts=%zu blocks_all_restarts=%zu "
               "ipsr_cg_steps=%zu ipsr_faces=%zu ipsr_reused=%zu "
               "seconds=%.3f peak_rss_mb=%.1f\n",
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
               s.sensor_turned,
               s.frame_sensors,
               s.frame_turned,
               s.scan_kind == DACPO_SCAN_SINGLE_VIEW ? "single" : "multi",
               s.single_view_fit,
               s.dipole_c_used,
               s.dipole_layers_used,
               s.dipole_two_sheet_used,
               s.layered_share,
               s.layered_copies,
               s.layered_doubled,
               s.layered_crossing,
               s.copy_scale_axes,
               s.dipole_sides_used,
               s.sign_flipped,
               s.sign_facing,
               s.sign_enclosed,
               s.solver_optimal ? 1 : 0,
               s.num_blocks ? static_cast<double>(s.ipsr_iterations_total) /
                                  static_cast<double>(s.num_blocks)
                            : 0.0,
               s.ipsr_iterations_max,
               s.dipole_restarts_total,
               s.dipole_blocks_all_restarts,
               s.ipsr_cg_iterations_total,
               s.ipsr_faces_total,
               s.ipsr_surfaces_reused,
               s.total_seconds,
               peakRssMb());
}

} // namespace orient_tool
