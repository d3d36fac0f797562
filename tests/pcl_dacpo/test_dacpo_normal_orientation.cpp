// SPDX-License-Identifier: BSD-3-Clause
// pcl::DACPONormalOrientation: orientation quality on synthetic scenes (estimated
// and given normals), the PCL conventions (indices, NaN points, output order,
// k, radius, empty input) and the C-boundary rules (exceptions, cancellation).
#include <dacpo/dacpo.h>

#include <pcl_dacpo/dacpo_normal_orientation.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <gtest/gtest.h>

#include "dacpo_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace {
using Orientation = pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal>;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/** A generated scene as PCL clouds: positions, ground truth and scrambled axes. */
struct Scene {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud{new pcl::PointCloud<pcl::PointXYZ>};
  pcl::PointCloud<pcl::Normal>::Ptr scrambled{new pcl::PointCloud<pcl::Normal>};
  std::vector<float> gt; // 3 per point
};

Scene
makeScene(unsigned kind, std::size_t points, std::uint64_t seed = 1)
{
  dacpo_scene_params p;
  dacpo_scene_params_init(&p);
  p.kind = kind;
  p.target_points = points;
  p.seed = seed;
  dacpo_scene s;
  char err[256];
  Scene out;
  if (dacpo_scene_generate(&p, &s, err, sizeof(err)) != 0) {
    ADD_FAILURE() << "scene generation failed: " << err;
    return out;
  }
  std::vector<float> flipped(3 * s.n);
  dacpo_scene_scramble_signs(&s, flipped.data(), seed + 100, 0.5);
  out.gt.assign(s.normals, s.normals + 3 * s.n);
  for (std::size_t i = 0; i < s.n; ++i) {
    out.cloud->push_back(
        pcl::PointXYZ(s.xyz[3 * i], s.xyz[3 * i + 1], s.xyz[3 * i + 2]));
    pcl::Normal n(flipped[3 * i], flipped[3 * i + 1], flipped[3 * i + 2]);
    n.curvature = 0.25f;
    out.scrambled->push_back(n);
  }
  dacpo_scene_free(&s);
  return out;
}

/** Paper metric (% wrong after one global flip) over the points with finite
 *  output normals; \a labels gives each component its own sign when not NULL. */
template <typename PointT>
double
wrongPercent(const std::vector<float>& gt,
             const pcl::PointCloud<PointT>& out,
             const std::vector<int>* labels = nullptr)
{
  std::vector<float> pred(3 * out.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    pred[3 * i] = out[i].normal_x;
    pred[3 * i + 1] = out[i].normal_y;
    pred[3 * i + 2] = out[i].normal_z;
  }
  std::vector<std::int32_t> l;
  if (labels)
    l.assign(labels->begin(), labels->end());
  return dacpo_score_oriented(
      gt.data(), pred.data(), out.size(), labels ? l.data() : nullptr, nullptr);
}

bool
isUnit(const pcl::Normal& n)
{
  const double len =
      std::sqrt(double(n.normal_x) * n.normal_x + double(n.normal_y) * n.normal_y +
                double(n.normal_z) * n.normal_z);
  return std::fabs(len - 1.0) < 1e-3;
}

/** Fails every query: the exception must not cross into the C core. */
class ThrowingSearch : public pcl::search::KdTree<pcl::PointXYZ> {
public:
  int
  nearestKSearch(const pcl::PointXYZ&,
                 int,
                 pcl::Indices&,
                 std::vector<float>&) const override
  {
    throw std::runtime_error("search exploded");
  }
};

// Thresholds (paper metric, % wrong) from measurements with margin; a broken
// index mapping gives ~50 %, one flipped wall of the box ~20 %. Measured:
// box 10k full pipeline 0.0 %; two rooms 20k given normals, no iPSR 0.07 %;
// furnished room 20k given normals, no iPSR 9.0 % (thin objects need iPSR, which
// is too slow for a unit test at that size).
constexpr double kMaxWrongBox = 2.0;
constexpr double kMaxWrongTwoRooms = 2.0;
constexpr double kMaxWrongRoomNoIPSR = 15.0;

/** Most behaviour tests skip stage 3 (iPSR) to stay fast. */
template <typename Dacpo>
void
skipIPSR(Dacpo& dacpo)
{
  dacpo.setIPSREnabled(false);
}

TEST(DACPONormalOrientation, OrientsOpenBoxWithEstimatedNormals)
{
  // The whole pipeline, iPSR included.
  const Scene scene = makeScene(DACPO_SCENE_BOX_OPEN, 10000);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  EXPECT_EQ(dacpo.getKSearch(), 10);
  EXPECT_TRUE(dacpo.getIPSREnabled());
  EXPECT_FALSE(dacpo.hasInputNormals());
  dacpo.setInputCloud(scene.cloud);
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out);
  ASSERT_EQ(out.size(), scene.cloud->size());
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::OK);
  EXPECT_TRUE(out.is_dense);
  for (const auto& n : out)
    ASSERT_TRUE(isUnit(n));
  EXPECT_LT(wrongPercent(scene.gt, out), kMaxWrongBox);
  const dacpo_stats s = dacpo.getStats();
  EXPECT_EQ(s.input_points, scene.cloud->size());
  EXPECT_EQ(s.num_components, 1u);
  EXPECT_GE(s.num_blocks, 1u);
  EXPECT_EQ(dacpo.getBlockFlips().size(), s.num_blocks);
  EXPECT_EQ(dacpo.getEdges().size(), s.num_block_edges);
  ASSERT_EQ(dacpo.getBlockLabels().size(), out.size());
  for (int b : dacpo.getBlockLabels())
    ASSERT_TRUE(b >= 0 && static_cast<std::size_t>(b) < s.num_blocks);
  // PCA surface variation lies in [0, 1/3].
  for (const auto& n : out)
    ASSERT_TRUE(n.curvature >= 0.0f && n.curvature <= 0.34f);
}

TEST(DACPONormalOrientation, OrientsTwoRoomsWithGivenNormals)
{
  const Scene scene = makeScene(DACPO_SCENE_TWO_ROOMS, 20000);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::PointNormal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(scene.cloud);
  dacpo.setInputNormals(scene.scrambled);
  EXPECT_TRUE(dacpo.hasInputNormals());
  EXPECT_EQ(dacpo.getParameters().estimate_normals, 0);
  pcl::PointCloud<pcl::PointNormal> out;
  dacpo.compute(out);
  ASSERT_EQ(out.size(), scene.cloud->size());
  EXPECT_LT(wrongPercent(scene.gt, out), kMaxWrongTwoRooms);
  for (std::size_t i = 0; i < out.size(); ++i) {
    // Same order as the input, xyz copied, axis kept (only the sign may change),
    // curvature copied from the given normals.
    ASSERT_EQ(out[i].x, (*scene.cloud)[i].x);
    ASSERT_EQ(out[i].z, (*scene.cloud)[i].z);
    const pcl::Normal& g = (*scene.scrambled)[i];
    const double dot = out[i].normal_x * g.normal_x + out[i].normal_y * g.normal_y +
                       out[i].normal_z * g.normal_z;
    ASSERT_NEAR(std::fabs(dot), 1.0, 1e-4) << "point " << i;
    ASSERT_EQ(out[i].curvature, 0.25f);
  }
}

TEST(DACPONormalOrientation, OrientsFurnishedRoomWithoutIPSR)
{
  const Scene scene = makeScene(DACPO_SCENE_ROOM, 20000);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(scene.cloud);
  dacpo.setInputNormals(scene.scrambled);
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out);
  ASSERT_EQ(out.size(), scene.cloud->size());
  EXPECT_LT(wrongPercent(scene.gt, out), kMaxWrongRoomNoIPSR);
}

TEST(DACPONormalOrientation, CopiesSharedFieldsOfOtherPointTypes)
{
  const Scene scene = makeScene(DACPO_SCENE_BOX_OPEN, 5000);
  pcl::PointCloud<pcl::PointXYZRGB>::Ptr rgb(new pcl::PointCloud<pcl::PointXYZRGB>);
  for (const auto& p : *scene.cloud) {
    pcl::PointXYZRGB q(std::uint8_t(10), std::uint8_t(20), std::uint8_t(30));
    q.x = p.x;
    q.y = p.y;
    q.z = p.z;
    rgb->push_back(q);
  }
  pcl::DACPONormalOrientation<pcl::PointXYZRGB, pcl::PointXYZRGBNormal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(rgb);
  pcl::PointCloud<pcl::PointXYZRGBNormal> out;
  dacpo.compute(out);
  ASSERT_EQ(out.size(), rgb->size());
  EXPECT_EQ(out[17].r, 10);
  EXPECT_EQ(out[17].b, 30);
  EXPECT_EQ(out[17].y, (*rgb)[17].y);
  EXPECT_LT(wrongPercent(scene.gt, out), 10.0);
}

TEST(DACPONormalOrientation, NaNPointsGetNaNNormals)
{
  Scene scene = makeScene(DACPO_SCENE_BOX_OPEN, 10000);
  const std::vector<std::size_t> bad = {0, 7, 4242, 9999};
  for (std::size_t i : bad)
    (*scene.cloud)[i].y = (i == 7) ? std::numeric_limits<float>::infinity() : kNaN;
  scene.cloud->is_dense = false;
  // A zero given normal is skipped the same way.
  (*scene.scrambled)[100].normal_x = (*scene.scrambled)[100].normal_y =
      (*scene.scrambled)[100].normal_z = 0.0f;

  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(scene.cloud);
  dacpo.setInputNormals(scene.scrambled);
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out);
  ASSERT_EQ(out.size(), scene.cloud->size());
  EXPECT_FALSE(out.is_dense);
  std::vector<float> gt_ok;
  pcl::PointCloud<pcl::Normal> ok;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const bool skipped = i == 100 || std::find(bad.begin(), bad.end(), i) != bad.end();
    if (skipped) {
      EXPECT_TRUE(std::isnan(out[i].normal_x)) << "point " << i;
      EXPECT_TRUE(std::isnan(out[i].curvature)) << "point " << i;
      EXPECT_EQ(dacpo.getComponentLabels()[i], -1);
      continue;
    }
    ASSERT_TRUE(isUnit(out[i])) << "point " << i;
    ok.push_back(out[i]);
    gt_ok.insert(gt_ok.end(), &scene.gt[3 * i], &scene.gt[3 * i + 3]);
  }
  EXPECT_EQ(dacpo.getStats().input_points, out.size() - 5);
  EXPECT_LT(wrongPercent(gt_ok, ok), kMaxWrongBox);
}

TEST(DACPONormalOrientation, IndicesSelectTheOrientedPoints)
{
  const Scene scene = makeScene(DACPO_SCENE_BOX_OPEN, 20000);
  // Every second point of the half room x < 2: a subset both sparse and cropped,
  // so the search must skip neighbours outside the indices.
  pcl::IndicesPtr indices(new pcl::Indices);
  for (std::size_t i = 0; i < scene.cloud->size(); i += 2)
    if ((*scene.cloud)[i].x < 2.0f)
      indices->push_back(static_cast<pcl::index_t>(i));
  ASSERT_GT(indices->size(), 3000u);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(scene.cloud);
  dacpo.setIndices(indices);
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out);
  ASSERT_EQ(out.size(), indices->size());
  EXPECT_EQ(out.width, indices->size());
  EXPECT_EQ(dacpo.getStats().input_points, indices->size());
  std::vector<float> gt_sub;
  for (pcl::index_t i : *indices)
    gt_sub.insert(gt_sub.end(), &scene.gt[3 * i], &scene.gt[3 * i + 3]);
  EXPECT_LT(wrongPercent(gt_sub, out), 10.0);
}

TEST(DACPONormalOrientation, KLargerThanCloudIsClamped)
{
  const Scene scene = makeScene(DACPO_SCENE_PLANE, 60);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  dacpo.setInputCloud(scene.cloud);
  dacpo.setKSearch(200);
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out); // PCL_WARN: k clamped
  ASSERT_EQ(out.size(), scene.cloud->size()) << dacpo.getLastError();
  EXPECT_EQ(dacpo.getStats().k_clamped, 1);
  EXPECT_LT(dacpo.getStats().k_used, scene.cloud->size());
  EXPECT_LT(wrongPercent(scene.gt, out), 1.0);
}

TEST(DACPONormalOrientation, RadiusSearchIsRejected)
{
  const Scene scene = makeScene(DACPO_SCENE_PLANE, 500);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  dacpo.setInputCloud(scene.cloud);
  dacpo.setKSearch(0);
  dacpo.setRadiusSearch(0.2);
  pcl::PointCloud<pcl::Normal> out;
  out.resize(3);
  dacpo.compute(out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(out.width, 0u);
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::InvalidArgument);
  EXPECT_FALSE(dacpo.getLastError().empty());

  // radius and k both set: PCL's initCompute rejects it before the class runs
  dacpo.setKSearch(10);
  dacpo.compute(out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::InvalidArgument);
  EXPECT_NE(dacpo.getLastError().find("radius"), std::string::npos)
      << dacpo.getLastError();

  // a good run afterwards clears the verdict
  dacpo.setRadiusSearch(0.0);
  skipIPSR(dacpo);
  dacpo.compute(out);
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::OK);
  EXPECT_TRUE(dacpo.getLastError().empty());
}

TEST(DACPONormalOrientation, EmptyCloudGivesEmptyOutput)
{
  pcl::PointCloud<pcl::PointXYZ>::Ptr empty(new pcl::PointCloud<pcl::PointXYZ>);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(empty);
  pcl::PointCloud<pcl::Normal> out;
  out.resize(5);
  dacpo.compute(out); // PCL's initCompute rejects it; the class says why
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::EmptyInput);
  EXPECT_NE(dacpo.getLastError().find("empty"), std::string::npos)
      << dacpo.getLastError();

  // Only non-finite points: the wrapper reports EMPTY_INPUT.
  pcl::PointCloud<pcl::PointXYZ>::Ptr nan_only(new pcl::PointCloud<pcl::PointXYZ>);
  nan_only->push_back(pcl::PointXYZ(kNaN, 0, 0));
  nan_only->push_back(pcl::PointXYZ(0, kNaN, 0));
  nan_only->is_dense = false;
  dacpo.setInputCloud(nan_only);
  dacpo.compute(out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::EmptyInput);
}

TEST(DACPONormalOrientation, TwoFarApartClustersAreTwoComponents)
{
  Scene a = makeScene(DACPO_SCENE_SPHERE, 3000, 1);
  const Scene b = makeScene(DACPO_SCENE_SPHERE, 3000, 2);
  for (auto p : *b.cloud) {
    p.x += 100.0f;
    a.cloud->push_back(p);
  }
  a.gt.insert(a.gt.end(), b.gt.begin(), b.gt.end());
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  dacpo.setInputCloud(a.cloud);
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out); // PCL_WARN with the count
  ASSERT_EQ(out.size(), 6000u);
  EXPECT_EQ(dacpo.getStats().num_components, 2u);
  const std::vector<int>& labels = dacpo.getComponentLabels();
  EXPECT_EQ(labels.front(), 0);
  EXPECT_EQ(labels.back(), 1);
  EXPECT_LT(wrongPercent(a.gt, out, &labels), 2.0);

  dacpo.setDisconnectedPolicy(Orientation::DisconnectedPolicy::Error);
  EXPECT_EQ(dacpo.getDisconnectedPolicy(), Orientation::DisconnectedPolicy::Error);
  dacpo.compute(out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::Disconnected);
}

pcl::PointCloud<pcl::Normal>
runBox(const Scene& scene, std::uint64_t seed, unsigned threads, bool ipsr)
{
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  dacpo.setIPSREnabled(ipsr);
  dacpo.setInputCloud(scene.cloud);
  dacpo.setSeed(seed);
  dacpo.setNumberOfThreads(threads);
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out);
  return out;
}

bool
identical(const pcl::PointCloud<pcl::Normal>& a, const pcl::PointCloud<pcl::Normal>& b)
{
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), a.size() * sizeof(pcl::Normal)) == 0;
}

TEST(DACPONormalOrientation, SameSeedGivesIdenticalOutput)
{
  const Scene scene = makeScene(DACPO_SCENE_BOX_OPEN, 15000);
  const auto a = runBox(scene, 7, 1, false);
  const auto b = runBox(scene, 7, 1, false);
  ASSERT_EQ(a.size(), scene.cloud->size());
  EXPECT_TRUE(identical(a, b));
}

TEST(DACPONormalOrientation, ThreadCountDoesNotChangeOutput)
{
  // With iPSR: its blocks run in parallel.
  const Scene scene = makeScene(DACPO_SCENE_BOX_OPEN, 6000);
  const auto one = runBox(scene, 3, 1, true);
  const auto two = runBox(scene, 3, 2, true);
  ASSERT_EQ(one.size(), scene.cloud->size());
  EXPECT_TRUE(identical(one, two));
}

TEST(DACPONormalOrientation, SearchExceptionsDoNotCrossTheCBoundary)
{
  const Scene scene = makeScene(DACPO_SCENE_PLANE, 500);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(scene.cloud);
  dacpo.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new ThrowingSearch));
  pcl::PointCloud<pcl::Normal> out;
  EXPECT_NO_THROW(dacpo.compute(out));
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::NeighborSearch);
  EXPECT_NE(dacpo.getLastError().find("search exploded"), std::string::npos)
      << dacpo.getLastError();
}

TEST(DACPONormalOrientation, ProgressCallbackCanCancel)
{
  const Scene scene = makeScene(DACPO_SCENE_BOX_OPEN, 5000);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(scene.cloud);
  int calls = 0;
  double last = -1.0;
  dacpo.setProgressCallback([&](dacpo_stage, double f) {
    ++calls;
    last = f;
    return true;
  });
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out);
  EXPECT_EQ(out.size(), scene.cloud->size());
  EXPECT_GT(calls, 0);
  EXPECT_GE(last, 0.0);

  dacpo.setProgressCallback(
      [](dacpo_stage stage, double) { return stage < DACPO_STAGE_SEGMENT; });
  dacpo.compute(out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::Cancelled);

  dacpo.setProgressCallback([](dacpo_stage, double) -> bool {
    throw std::runtime_error("progress exploded");
  });
  EXPECT_NO_THROW(dacpo.compute(out));
  EXPECT_TRUE(out.empty());
}

TEST(DACPONormalOrientation, BadParametersAndNormalsSizeAreReported)
{
  const Scene scene = makeScene(DACPO_SCENE_PLANE, 500);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(scene.cloud);
  dacpo.setDipoleC(0.5); // paper Eq. 1 needs c >= 1 (or < 0: by the scan kind)
  EXPECT_EQ(dacpo.getDipoleC(), 0.5);
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::InvalidArgument);
  EXPECT_NE(dacpo.getLastError().find("dipole_c"), std::string::npos)
      << dacpo.getLastError();

  dacpo.setDipoleC(4.0);
  pcl::PointCloud<pcl::Normal>::Ptr few(new pcl::PointCloud<pcl::Normal>);
  few->resize(10);
  dacpo.setInputNormals(few);
  dacpo.compute(out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(dacpo.getLastStatus(), Orientation::Status::InvalidArgument);
  dacpo.resetInputNormals();
  dacpo.compute(out);
  EXPECT_EQ(out.size(), scene.cloud->size());
}

TEST(DACPONormalOrientation, SettersRoundTrip)
{
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> d;
  d.setNormalK(12);
  d.setNumberOfBlocks(7);
  d.setRingHops(2);
  d.setDipoleOrders(3);
  d.setDipoleNeighbors(16);
  d.setDipoleFinalSweep(false);
  d.setIPSREnabled(false);
  d.setIPSRMaxIterations(4);
  d.setEdgeWeight(Orientation::EdgeWeight::VCR);
  d.setSolverTimeLimit(2.5);
  d.setSeed(99);
  d.setNumberOfThreads(3);
  d.setDisconnectedPolicy(Orientation::DisconnectedPolicy::Bridge);
  EXPECT_EQ(d.getCueAnchor(), 1.0); // the default
  d.setCueAnchor(0.25);
  EXPECT_EQ(d.getSeamDipole(), 0.5);
  d.setSeamDipole(0.25);
  EXPECT_EQ(d.getSurfaceVote(), 500u);
  d.setSurfaceVote(250);
  d.setAdaptiveNormals(true);
  EXPECT_TRUE(d.getAdaptiveNormals());
  EXPECT_EQ(d.getNormalK(), 12u);
  EXPECT_EQ(d.getNumberOfBlocks(), 7u);
  EXPECT_EQ(d.getRingHops(), 2u);
  EXPECT_EQ(d.getDipoleOrders(), 3u);
  EXPECT_EQ(d.getDipoleNeighbors(), 16u);
  EXPECT_FALSE(d.getDipoleFinalSweep());
  EXPECT_FALSE(d.getIPSREnabled());
  EXPECT_EQ(d.getIPSRMaxIterations(), 4u);
  EXPECT_EQ(d.getEdgeWeight(), Orientation::EdgeWeight::VCR);
  EXPECT_EQ(d.getSolverTimeLimit(), 2.5);
  EXPECT_EQ(d.getSeed(), 99u);
  EXPECT_EQ(d.getNumberOfThreads(), 3u);
  EXPECT_EQ(d.getDisconnectedPolicy(), Orientation::DisconnectedPolicy::Bridge);
  const dacpo_params p = d.getParameters();
  EXPECT_EQ(p.k, 10u);
  EXPECT_EQ(p.estimate_normals, 1);
  EXPECT_EQ(p.num_blocks, 7u);
  EXPECT_EQ(p.cue_anchor, 0.25);
  EXPECT_EQ(p.seam_dipole, 0.25);
  EXPECT_EQ(p.surface_vote, 250u);
  EXPECT_EQ(p.adaptive_normals, 1);
  d.setNumberOfThreads();
  EXPECT_EQ(d.getNumberOfThreads(), 0u);
}

// setParameter takes any row of the parameter table by name, as the CLI does.
TEST(DACPONormalOrientation, SetParameterByName)
{
  using Orientation = pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal>;
  Orientation d;
  std::string error;
  EXPECT_TRUE(d.setParameter("dipole_c", "2", &error)) << error;
  EXPECT_EQ(d.getDipoleC(), 2.0);
  EXPECT_TRUE(d.setParameter("k", "14", &error)) << error;
  EXPECT_EQ(d.getKSearch(), 14);
  EXPECT_TRUE(d.setParameter("edge_weight", "dipole", &error)) << error;
  EXPECT_EQ(d.getEdgeWeight(), Orientation::EdgeWeight::DipoleBoundary);
  EXPECT_FALSE(d.setParameter("dipole_c", "two", &error));
  EXPECT_NE(error.find("dipole_c"), std::string::npos) << error;
  EXPECT_EQ(d.getDipoleC(), 2.0);
  EXPECT_FALSE(d.setParameter("no_such_field", "1", &error));
  EXPECT_NE(error.find("no_such_field"), std::string::npos) << error;
}

} // namespace

namespace {
/** % of output normals that agree with the ground truth as they are (no flip). */
double
rightAsGiven(const std::vector<float>& gt, const pcl::PointCloud<pcl::Normal>& out)
{
  std::size_t right = 0;
  for (std::size_t i = 0; i < out.size(); ++i)
    right += gt[3 * i] * out[i].normal_x + gt[3 * i + 1] * out[i].normal_y +
                 gt[3 * i + 2] * out[i].normal_z >
             0.0f;
  return out.empty() ? 0.0 : 100.0 * double(right) / double(out.size());
}
} // namespace

// The sign the caller gets: by default into the open box (free space); facing
// the cloud's sensor_origin_ or a given viewpoint when asked, like PCL's
// NormalEstimation, but one sign for the whole cloud.
TEST(DACPONormalOrientation, SignPolicyFacesFreeSpaceSensorOriginOrViewpoint)
{
  const Scene scene = makeScene(DACPO_SCENE_BOX_OPEN, 6000);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  skipIPSR(dacpo);
  EXPECT_EQ(dacpo.getSignPolicy(), Orientation::SignPolicy::FreeSpace);
  dacpo.setInputCloud(scene.cloud);
  dacpo.setInputNormals(scene.scrambled);
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out);
  ASSERT_EQ(dacpo.getLastStatus(), Orientation::Status::OK);
  EXPECT_GT(rightAsGiven(scene.gt, out), 99.0);

  // a sensor far out below the x = 0, y = 0 corner (the box is [0, 4] x [0, 3]
  // x [0, 2.5]): the floor and the x = 0 and y = 0 walls (29.5 of 47 m^2) face
  // away from it as they are, so the one sign that makes most normals face it
  // (29.5 / 47 = 63 % of the points) turns the whole box inside out
  pcl::PointCloud<pcl::PointXYZ>::Ptr moved(
      new pcl::PointCloud<pcl::PointXYZ>(*scene.cloud));
  moved->sensor_origin_ = Eigen::Vector4f(-1000.0f, -1000.0f, -1000.0f, 1.0f);
  dacpo.setInputCloud(moved);
  dacpo.useSensorOriginAsViewPoint();
  EXPECT_EQ(dacpo.getSignPolicy(), Orientation::SignPolicy::ViewPoint);
  dacpo.compute(out);
  ASSERT_EQ(dacpo.getLastStatus(), Orientation::Status::OK);
  EXPECT_LT(rightAsGiven(scene.gt, out), 1.0);
  EXPECT_NEAR(dacpo.getStats().sign_facing, 29.5 / 47.0, 0.03);
  EXPECT_EQ(dacpo.getStats().sign_viewpoint[2], -1000.0);

  // an explicit viewpoint inside the box wins over the sensor origin
  dacpo.setViewPoint(2.0f, 1.5f, 1.0f);
  float vx, vy, vz;
  dacpo.getViewPoint(vx, vy, vz);
  EXPECT_EQ(vz, 1.0f);
  dacpo.compute(out);
  EXPECT_GT(rightAsGiven(scene.gt, out), 99.0);
  EXPECT_GT(dacpo.getStats().sign_facing, 0.99);

  // KEEP: the method's own sign, the same normals up to one flip
  dacpo.setSignPolicy(Orientation::SignPolicy::Keep);
  pcl::PointCloud<pcl::Normal> kept;
  dacpo.compute(kept);
  EXPECT_EQ(dacpo.getStats().sign_flipped, 0);
  EXPECT_LT(wrongPercent(scene.gt, kept), kMaxWrongBox);
}

// An organized depth frame (64 x 48 pixels, a ball of radius 0.5 m in front of
// a wall) seen from a sensor that was then moved (rotated and shifted, as
// sensor_origin_ / sensor_orientation_ record it): useSensorOriginAsViewPoint()
// makes the normals face the sensor; the default free-space sign agrees.
TEST(DACPONormalOrientation, OrganizedFrameFacesItsSensorOrigin)
{
  const int W = 64, H = 48;
  pcl::PointCloud<pcl::PointXYZ>::Ptr frame(new pcl::PointCloud<pcl::PointXYZ>(W, H));
  std::vector<float> gt(3 * W * H);
  const Eigen::Vector3f centre(0.0f, 0.0f, -2.0f), shift(3.0f, -1.0f, 0.5f);
  const Eigen::Matrix3f rot =
      Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1.0f, 2.0f, 0.5f).normalized())
          .toRotationMatrix();
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      const Eigen::Vector3f ray =
          Eigen::Vector3f((u - W / 2 + 0.5f) / 40.0f, (v - H / 2 + 0.5f) / 40.0f, -1.0f)
              .normalized();
      // ray-ball intersection, else the wall z = -3
      const float b = ray.dot(centre), c = centre.squaredNorm() - 0.25f,
                  disc = b * b - c;
      Eigen::Vector3f p, n;
      if (disc > 0.0f) {
        p = ray * (b - std::sqrt(disc));
        n = (p - centre).normalized();
      }
      else {
        p = ray * (-3.0f / ray.z());
        n = Eigen::Vector3f(0.0f, 0.0f, 1.0f);
      }
      const std::size_t i = static_cast<std::size_t>(v) * W + u;
      (*frame)[i].getVector3fMap() = rot * p + shift;
      const Eigen::Vector3f truth = rot * n;
      for (int d = 0; d < 3; ++d)
        gt[3 * i + d] = truth[d];
    }
  frame->sensor_origin_ << shift, 0.0f;
  frame->sensor_orientation_ = Eigen::Quaternionf(rot);
  ASSERT_TRUE(frame->isOrganized());

  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  skipIPSR(dacpo);
  dacpo.setInputCloud(frame);
  dacpo.useSensorOriginAsViewPoint();
  pcl::PointCloud<pcl::Normal> out;
  dacpo.compute(out);
  ASSERT_EQ(dacpo.getLastStatus(), Orientation::Status::OK) << dacpo.getLastError();
  ASSERT_EQ(out.size(), frame->size());
  EXPECT_EQ(out.width, static_cast<std::uint32_t>(W));
  EXPECT_GT(rightAsGiven(gt, out), 99.0);
  EXPECT_GT(dacpo.getStats().sign_facing, 0.99);

  dacpo.setSignPolicy(Orientation::SignPolicy::FreeSpace);
  dacpo.compute(out);
  EXPECT_GT(rightAsGiven(gt, out), 99.0);
}

// The kept scene mesh as a pcl::PolygonMesh: triangles wound like the output
// normals (checked against the nearest output point of each triangle).
TEST(DACPONormalOrientation, KeptMeshAsPolygonMesh)
{
  const Scene scene = makeScene(DACPO_SCENE_BOX_OPEN, 4000);
  pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
  dacpo.setInputCloud(scene.cloud);
  pcl::PointCloud<pcl::Normal> out;
  pcl::PolygonMesh mesh;
  dacpo.compute(out);
  EXPECT_FALSE(dacpo.getMesh(mesh)) << "no mesh unless asked for";
  EXPECT_TRUE(mesh.polygons.empty());

  dacpo.setKeepMesh(true);
  dacpo.compute(out);
  ASSERT_EQ(dacpo.getLastStatus(), Orientation::Status::OK) << dacpo.getLastError();
  ASSERT_TRUE(dacpo.getMesh(mesh));
  pcl::PointCloud<pcl::PointXYZ> v;
  pcl::fromPCLPointCloud2(mesh.cloud, v);
  ASSERT_GT(mesh.polygons.size(), 1000u);
  std::size_t agree = 0;
  for (const pcl::Vertices& tri : mesh.polygons) {
    ASSERT_EQ(tri.vertices.size(), 3u);
    const Eigen::Vector3f a = v[tri.vertices[0]].getVector3fMap(),
                          b = v[tri.vertices[1]].getVector3fMap(),
                          c = v[tri.vertices[2]].getVector3fMap();
    const Eigen::Vector3f face = (b - a).cross(c - a), centre = (a + b + c) / 3.0f;
    std::size_t best = 0;
    float best_d = std::numeric_limits<float>::max();
    for (std::size_t i = 0; i < scene.cloud->size(); ++i) {
      const float d = ((*scene.cloud)[i].getVector3fMap() - centre).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = i;
      }
    }
    agree += face.dot(out[best].getNormalVector3fMap()) > 0.0f;
  }
  const double share = static_cast<double>(agree) / mesh.polygons.size();
  RecordProperty("mesh_winding_agrees", std::to_string(share));
  // measured 100 %; near corners the nearest point could lie on the other face
  EXPECT_GT(share, 0.95);
}
