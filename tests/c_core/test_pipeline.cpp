// SPDX-License-Identifier: BSD-3-Clause
// dacpo_orient() end to end, through the public C API only, on synthetic scenes
// with known normals (wrappers/support/dacpo_scene.h): orientation error against
// ground truth, the per-point / per-block / per-edge results and stats the
// context publishes, determinism (seed, thread count, caller's search), the
// progress callback's contract, that the output keeps the caller's axes, and
// that the run as work units (dacpo_advanced.h) gives dacpo_orient()'s answer.
#include <dacpo/dacpo.h>
#include <dacpo/dacpo_advanced.h>

#include <gtest/gtest.h>

#include "scene_fixture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace {

struct CtxDeleter {
  void
  operator()(dacpo_ctx* c) const
  {
    dacpo_ctx_free(c);
  }
};
using CtxPtr = std::unique_ptr<dacpo_ctx, CtxDeleter>;

CtxPtr
makeCtx()
{
  dacpo_ctx* c = nullptr;
  EXPECT_EQ(dacpo_ctx_create(&c), DACPO_OK);
  return CtxPtr(c);
}

using Scene = GeneratedScene;

// The scene's ground truth with half of the signs flipped.
std::vector<float>
scrambled(const Scene& sc, uint64_t seed)
{
  std::vector<float> n(3 * sc.s.n);
  dacpo_scene_scramble_signs(&sc.s, n.data(), seed, 0.5);
  return n;
}

// Everything one run leaves in the context, copied out.
struct Result {
  dacpo_status status = DACPO_ERR_INTERNAL;
  std::string error;
  std::vector<float> normals;
  dacpo_stats stats{};
  std::vector<int32_t> component, block;
  std::vector<float> curvature; // empty when normals were given
  std::vector<float> confidence;
  std::vector<uint8_t> flips;
  std::vector<dacpo_edge_info> edges;
};

// What the context holds after a run that returned r.status.
void
collect(dacpo_ctx* ctx, Result& r)
{
  r.error = dacpo_ctx_last_error(ctx);
  r.stats = *dacpo_ctx_stats(ctx);
  if (r.status != DACPO_OK)
    return;
  const size_t m = r.stats.input_points;
  if (const int32_t* c = dacpo_ctx_point_components(ctx))
    r.component.assign(c, c + m);
  if (const int32_t* b = dacpo_ctx_point_blocks(ctx))
    r.block.assign(b, b + m);
  if (const float* k = dacpo_ctx_point_curvature(ctx))
    r.curvature.assign(k, k + m);
  if (const float* c = dacpo_ctx_point_confidence(ctx))
    r.confidence.assign(c, c + m);
  if (const uint8_t* f = dacpo_ctx_block_flips(ctx))
    r.flips.assign(f, f + r.stats.num_blocks);
  if (const dacpo_edge_info* e = dacpo_ctx_edges(ctx))
    r.edges.assign(e, e + r.stats.num_block_edges);
}

Result
orient(dacpo_ctx* ctx,
       const dacpo_params& p,
       const float* xyz,
       std::vector<float> normals,
       size_t n,
       const dacpo_search* search = nullptr,
       const dacpo_progress* progress = nullptr)
{
  Result r;
  r.status = dacpo_orient(ctx, &p, search, progress, xyz, normals.data(), n);
  r.normals = std::move(normals);
  collect(ctx, r);
  return r;
}

Result
orientScene(const Scene& sc,
            const dacpo_params& p,
            const dacpo_search* search = nullptr,
            const dacpo_progress* progress = nullptr)
{
  auto ctx = makeCtx();
  std::vector<float> in =
      p.estimate_normals ? std::vector<float>(3 * sc.s.n, 0.0f) : scrambled(sc, 7);
  return orient(ctx.get(), p, sc.s.xyz, std::move(in), sc.s.n, search, progress);
}

// Percentage of wrong normals, one free sign for the whole scene.
double
wrongPercent(const Scene& sc, const Result& r)
{
  return dacpo_score_oriented(sc.s.normals, r.normals.data(), sc.s.n, nullptr, nullptr);
}

bool
sameBits(const std::vector<float>& a, const std::vector<float>& b)
{
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

// Two runs that must agree bit for bit.
void
expectSameRun(const Result& a, const Result& b)
{
  ASSERT_EQ(a.status, DACPO_OK) << a.error;
  ASSERT_EQ(b.status, DACPO_OK) << b.error;
  EXPECT_TRUE(sameBits(a.normals, b.normals));
  EXPECT_TRUE(sameBits(a.confidence, b.confidence));
  EXPECT_EQ(a.block, b.block);
  EXPECT_EQ(a.component, b.component);
  EXPECT_EQ(a.flips, b.flips);
  ASSERT_EQ(a.edges.size(), b.edges.size());
  for (size_t e = 0; e < a.edges.size(); ++e) {
    EXPECT_EQ(a.edges[e].alpha, b.edges[e].alpha) << e;
    EXPECT_EQ(a.edges[e].alpha_bar, b.edges[e].alpha_bar) << e;
  }
  EXPECT_EQ(a.stats.num_blocks, b.stats.num_blocks);
  EXPECT_EQ(a.stats.ipsr_iterations_total, b.stats.ipsr_iterations_total);
  EXPECT_EQ(a.stats.solver_objective, b.stats.solver_objective);
}

dacpo_params
defaults()
{
  dacpo_params p;
  dacpo_params_init(&p);
  return p;
}

// Brute-force k nearest neighbours over the caller's arrays, nearest first,
// ties to the lower index, distances in double (as the core ranks them).
struct BruteForce {
  const float* xyz;
  size_t n;
};

int
bruteForceKnn(
    void* user, size_t query, size_t k, int32_t* idx, float* sqd, size_t* found)
{
  const auto* bf = static_cast<const BruteForce*>(user);
  if (query >= bf->n)
    return 1;
  std::vector<std::pair<double, int32_t>> all(bf->n);
  const float* q = bf->xyz + 3 * query;
  for (size_t j = 0; j < bf->n; ++j) {
    const float* x = bf->xyz + 3 * j;
    double dx = double(q[0]) - x[0], dy = double(q[1]) - x[1], dz = double(q[2]) - x[2];
    all[j] = {dx * dx + dy * dy + dz * dz, static_cast<int32_t>(j)};
  }
  const size_t m = std::min(k, bf->n);
  std::partial_sort(all.begin(), all.begin() + m, all.end());
  for (size_t j = 0; j < m; ++j) {
    idx[j] = all[j].second;
    sqd[j] = static_cast<float>(all[j].first);
  }
  *found = m;
  return 0;
}

struct ProgressLog {
  std::vector<std::pair<int, double>> calls;
  std::thread::id caller = std::this_thread::get_id();
  size_t off_thread = 0;
};

int
logProgress(void* user, dacpo_stage stage, double fraction)
{
  auto* log = static_cast<ProgressLog*>(user);
  log->calls.emplace_back(static_cast<int>(stage), fraction);
  if (std::this_thread::get_id() != log->caller)
    log->off_thread++;
  return 0;
}

} // namespace

// ---- known answers ---------------------------------------------------------

// Measured (seed 1, 10K points, defaults): 0.000 % wrong with given and with
// estimated normals, also for scene seeds 2-4; the 1 % bound leaves margin for
// platform differences while catching any wrongly flipped wall or floor block
// (the smallest wall is ~16 % of the points).
TEST(DacpoPipeline, OpenBoxScrambledNormals)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 1);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 10000u);
  Result r = orientScene(sc, defaults());
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  const double wrong = wrongPercent(sc, r);
  RecordProperty("wrong_percent", std::to_string(wrong));
  EXPECT_LT(wrong, 1.0);
  EXPECT_EQ(r.stats.num_components, 1u);
  EXPECT_GT(r.stats.num_blocks, 1u) << "the block graph and 0-1 program should be used";
  EXPECT_TRUE(r.curvature.empty())
      << "curvature is only published for estimated normals";
}

TEST(DacpoPipeline, OpenBoxEstimatedNormals)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 1);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 10000u);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  Result r = orientScene(sc, p);
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  const double wrong = wrongPercent(sc, r);
  RecordProperty("wrong_percent", std::to_string(wrong));
  EXPECT_LT(wrong, 1.0);
  ASSERT_EQ(r.curvature.size(), sc.s.n);
}

// Measured (30K points, defaults, given normals): 1.33 % wrong for scene seed 1
// (the errors sit on the thin door jambs), 0 % for seeds 2-4, 2.34 % with
// estimated normals. A wrongly flipped wall block alone costs > 3 %.
TEST(DacpoPipeline, TwoRoomsBelowMeasuredError)
{
  Scene sc(DACPO_SCENE_TWO_ROOMS, 30000, 1);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 30000u);
  Result r = orientScene(sc, defaults());
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  const double wrong = wrongPercent(sc, r);
  RecordProperty("wrong_percent", std::to_string(wrong));
  EXPECT_LT(wrong, 3.0);
  EXPECT_GE(r.stats.num_blocks, 8u);
  EXPECT_EQ(r.stats.solver_optimal, 1);
}

// Measured (20K-point room, estimated normals, defaults): seeds 1-5 give 8.98,
// 9.86, 8.83, 8.81, 8.83 % wrong (spread 1.05 points; with 4 restarts kept by
// energy 9.31, 11.07, 9.44, 8.96, 9.21 %, spread 2.1; most of it on thin
// furniture inside blocks). Before stage-2 restarts, magnitude-aware edge
// weights and related parts, single seeds of such rooms swung by up to 22
// points. The least confident 10 % of the points held 40-44 % of the wrong ones.
TEST(DacpoPipeline, SeedsOneToFiveAgreeOnAGeneratedRoom)
{
  Scene sc(DACPO_SCENE_ROOM, 20000, 1);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 20000u);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  double lo = 100.0, hi = 0.0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    p.seed = seed;
    Result r = orientScene(sc, p);
    ASSERT_EQ(r.status, DACPO_OK) << r.error;
    const double wrong = wrongPercent(sc, r);
    lo = std::min(lo, wrong);
    hi = std::max(hi, wrong);
    EXPECT_LT(wrong, 13.0);

    // Confidence: in [0, 1], and the least confident 10 % hold far more than
    // 10 % of the wrong points.
    ASSERT_EQ(r.confidence.size(), sc.s.n);
    std::vector<size_t> order(sc.s.n);
    for (size_t i = 0; i < sc.s.n; ++i) {
      order[i] = i;
      ASSERT_GE(r.confidence[i], 0.0f) << i;
      ASSERT_LE(r.confidence[i], 1.0f) << i;
    }
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
      return r.confidence[a] < r.confidence[b];
    });
    // wrong under the sign that makes most points right
    size_t agree = 0;
    std::vector<bool> right(sc.s.n);
    for (size_t i = 0; i < sc.s.n; ++i) {
      const float* g = sc.s.normals + 3 * i;
      const float* o = r.normals.data() + 3 * i;
      right[i] = g[0] * o[0] + g[1] * o[1] + g[2] * o[2] > 0.0f;
      agree += right[i];
    }
    const bool flip = 2 * agree < sc.s.n;
    size_t wrong_all = 0, wrong_low = 0;
    for (size_t k = 0; k < sc.s.n; ++k) {
      const bool w = right[order[k]] == flip;
      wrong_all += w;
      wrong_low += w && k < sc.s.n / 10;
    }
    EXPECT_GT(static_cast<double>(wrong_low), 0.3 * static_cast<double>(wrong_all));
  }
  RecordProperty("seed_spread", std::to_string(hi - lo));
  EXPECT_LE(hi - lo, 3.0);
}

// A room seen by 20 depth cameras and nothing else (dacpo_make_scene -n
// 100000 -views 20,0,0 -seed 3): every surface faces the cameras that saw
// it. The face of a 10 cm partition (7,493 points) meets the floor only
// through seven seams below the median evidence, all saying "same"; weighed
// one by one they left the face to the viewpoint vote, and the viewpoint
// found stands behind the partition. Measured (estimated normals, run seed
// 3): 16.61 % wrong then, 4.83 % since groups join by the net evidence of
// all their seams, 4.99 % since parts vote with cosines (CGAL's MST on the
// same points: 4.48 %).
// Each view's points (n / views each, the first n % views views one more)
// in a random order of their own instead of row by row.
void
shuffleEachView(dacpo_scene* s, unsigned views)
{
  std::mt19937_64 rng(7);
  for (size_t v = 0, first = 0; v < views; ++v) {
    const size_t count = s->n / views + (v < s->n % views ? 1 : 0);
    for (size_t j = count; j > 1; --j) {
      const size_t a = first + j - 1, b = first + rng() % j;
      for (int c = 0; c < 3; ++c) {
        std::swap(s->xyz[3 * a + c], s->xyz[3 * b + c]);
        std::swap(s->normals[3 * a + c], s->normals[3 * b + c]);
      }
      std::swap(s->part[a], s->part[b]);
    }
    first += count;
  }
}

// The generated room seen by `views` depth cameras (pose error per view:
// shift metres, angle degrees; none by default), oriented from estimated
// normals: the run's stats and its % wrong. shuffled: each view's points in
// a random order of their own.
void
orientViewedRoom(uint64_t scene_seed,
                 uint64_t run_seed,
                 Result* r,
                 double* wrong,
                 double shift = 0.0,
                 double angle = 0.0,
                 unsigned views = 20,
                 bool shuffled = false)
{
  dacpo_scene_params sp = Scene::params(DACPO_SCENE_ROOM, 100000, scene_seed);
  sp.views = views;
  sp.view_shift = shift;
  sp.view_angle = angle;
  Scene sc(sp);
  ASSERT_TRUE(sc.ok);
  if (shuffled)
    shuffleEachView(&sc.s, views);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  p.seed = run_seed;
  *r = orientScene(sc, p);
  ASSERT_EQ(r->status, DACPO_OK) << r->error;
  *wrong = wrongPercent(sc, *r);
}

TEST(DacpoPipeline, WeakSeamsTogetherHoldAFaceToTheFloor)
{
  Result r;
  double wrong = 100.0;
  ASSERT_NO_FATAL_FAILURE(orientViewedRoom(3, 3, &r, &wrong));
  printf("depth-camera room, scene seed 3, run seed 3: %.2f %% wrong\n", wrong);
  RecordProperty("wrong_percent", std::to_string(wrong));
  EXPECT_LT(wrong, 8.0);
}

// A room seen by 20 depth cameras all round (scene seed 5) passes for one view
// (the density fit 0.573 reaches 0.5) but its sensor is not one place: the
// position the density finds stands over the room's middle, and other cameras
// saw the far face of a 10 cm partition, squarely away from it. Turning the
// points it sees squarely to face it took this room from 6.69 to 18.22 %
// wrong (run seed 1); that pass needs a view the density explains well
// (single_view_fit >= 0.7), and here it must turn nothing.
TEST(DacpoPipeline, ManyViewsThatPassForOneKeepTheirSigns)
{
  Result r;
  double wrong = 100.0;
  ASSERT_NO_FATAL_FAILURE(orientViewedRoom(5, 1, &r, &wrong));
  printf("depth-camera room, scene seed 5: %.2f %% wrong, fit %.3f, %zu turned\n",
         wrong,
         r.stats.single_view_fit,
         r.stats.sensor_turned);
  EXPECT_EQ(r.stats.scan_kind, DACPO_SCAN_SINGLE_VIEW);
  EXPECT_EQ(r.stats.sensor_turned, 0u);
  EXPECT_LT(wrong, 10.0);
}

// Five depth cameras 5 mm / 0.1 degrees apart (scene seed 1, each view's
// points shuffled): the density fits one of them well enough (0.77) for the
// last sign pass, but the position it finds is that camera's mirror image
// outside the room: of the points it sees squarely 20,097 face away and
// 36,320 face it (real depth frames: at most one away in nineteen facing).
// Turning those took this room from 0.10 to 20.01 % wrong (run seed 1); the
// pass must leave them. (With the views row by row the parts' viewpoint
// already turns the first camera's 20,000 points inside out, 20.01 %, and
// none of that frame's windows finds a sensor: docs/DESIGN.md, known
// limits.)
TEST(DacpoPipeline, AFewFramesThatPassForOneKeepTheirSigns)
{
  Result r;
  double wrong = 100.0;
  ASSERT_NO_FATAL_FAILURE(orientViewedRoom(1, 1, &r, &wrong, 0.005, 0.1, 5, true));
  printf("five depth cameras, scene seed 1: %.2f %% wrong, fit %.3f, %zu turned\n",
         wrong,
         r.stats.single_view_fit,
         r.stats.sensor_turned);
  EXPECT_EQ(r.stats.scan_kind, DACPO_SCAN_SINGLE_VIEW);
  EXPECT_GE(r.stats.single_view_fit, 0.7); /* the pass is armed */
  EXPECT_EQ(r.stats.sensor_turned, 0u);
  EXPECT_LT(wrong, 2.0);
}

// Eight depth cameras 5 mm / 0.1 degrees apart (scene seed 6): copies under
// half a spacing apart that the floor does not show, so the side cue stays on
// and reads a wall's copies as a thin solid's two faces. Its 3,487 cue points
// are 14 % of the part they lie in (the east wall and the floor beside it,
// 25,519 points, joined to the rest by weak seams); when that part followed
// them it came out inside out: 26.30 % wrong instead of 1.31 % (run seed 1).
// A part follows the cue only where its cue points cover a quarter of it.
TEST(DacpoPipeline, AFewCopiesOfAWallDoNotTurnItsPart)
{
  Result r;
  double wrong = 100.0;
  ASSERT_NO_FATAL_FAILURE(orientViewedRoom(6, 1, &r, &wrong, 0.005, 0.1, 8));
  printf("eight depth cameras, scene seed 6: %.2f %% wrong, %zu blocks anchored, "
         "%zu parts signed by the cue\n",
         wrong,
         r.stats.cue_anchored_blocks,
         r.stats.parts_cue_signed);
  EXPECT_EQ(r.stats.scan_kind, DACPO_SCAN_MULTI_VIEW);
  EXPECT_GT(r.stats.cue_anchored_blocks, 0u); /* the cue is on here */
  EXPECT_EQ(r.stats.parts_cue_signed, 0u);
  EXPECT_LT(wrong, 5.0);
}

// Five depth cameras 5 mm / 0.1 degrees apart (scene seed 6), run seed 1: a
// 10 cm partition seen from both sides, mostly from one (its faces hold about
// 20,000 and 2,300 points), is the largest part of the scan, the one the
// viewpoint vote relates the others to. Stage 5 left it inside out, the vote
// kept it so, and 26,965 points came out wrong (27.25 %); as a slab whose
// face points, both faces and the band between them, vote that they look
// into it, it is turned over after the global sign.
TEST(DacpoPipeline, APartitionThatIsTheLargestPartFacesOut)
{
  Result r;
  double wrong = 100.0;
  ASSERT_NO_FATAL_FAILURE(orientViewedRoom(6, 1, &r, &wrong, 0.005, 0.1, 5));
  printf("five depth cameras, scene seed 6: %.2f %% wrong\n", wrong);
  EXPECT_LT(wrong, 2.0);
}

// Generated rooms seen by 20 depth cameras: a 10 cm partition whose face is
// a part of its own (weak seams to the floor, all right) and the one
// viewpoint the parts imply. Scene seed 6: the viewpoint stands over the
// partition's far edge, in the plane of its face, so every point of the face
// faced away from it by a hair and a vote of signs turned the face over
// (9,386 points, margin 0.55). Scene seed 5 with 10 mm / 0.3 degrees of pose
// error per view: the same at the corner of a partition whose other face the
// cameras barely saw (17,110 points, margin 0.77). Voting with cosines, the
// face seen edge-on has no say and keeps its seams. Measured (run seed 1):
// 11.33 -> 3.06 % and 23.79 -> 7.04 % wrong (CGAL's MST: 11.04 and 6.28 %).
TEST(DacpoPipeline, APartSeenEdgeOnKeepsItsSeams)
{
  struct Case {
    uint64_t scene;
    double shift, angle, most;
  };
  for (const Case& c : {Case{6, 0.0, 0.0, 5.0}, Case{5, 0.01, 0.3, 10.0}}) {
    Result r;
    double wrong = 100.0;
    ASSERT_NO_FATAL_FAILURE(orientViewedRoom(c.scene, 1, &r, &wrong, c.shift, c.angle));
    printf("depth-camera room, scene seed %llu, pose error %.0f mm: %.2f %% wrong\n",
           (unsigned long long)c.scene,
           1000.0 * c.shift,
           wrong);
    EXPECT_LT(wrong, c.most) << "scene seed " << c.scene;
  }
}

// The same room of scene seed 6 on run seed 2: the viewpoint stands in the
// room, the partition's two faces are one part, and its hidden face (5,894
// points) outvoted its visible one (3,491): the part came out inside out.
// A flat part with two faces looks away from its mid-plane whatever its
// size; the partition spans 0.29 of the room's diagonal, above the quarter
// up to which a closed part counts as an object, and was left to the vote.
// Measured (run seeds 2 / 3): 11.11 / 10.95 -> 1.70 / 1.56 % wrong.
TEST(DacpoPipeline, APartitionsFacesLookAwayFromEachOther)
{
  Result r;
  double wrong = 100.0;
  ASSERT_NO_FATAL_FAILURE(orientViewedRoom(6, 2, &r, &wrong));
  printf("depth-camera room, scene seed 6, run seed 2: %.2f %% wrong\n", wrong);
  EXPECT_LT(wrong, 5.0);
}

// A closed object that touches nothing (a ball hung above a room, sampled all
// round) faces every viewpoint with half its points: the viewpoint vote that
// relates disconnected parts cannot place it (without the closed-part rule it
// came out inside out on seeds 1-3). It must come out facing outward, in the
// frame where the room is right, on every seed.
TEST(DacpoPipeline, AFreeClosedObjectFacesOutward)
{
  Scene sc(DACPO_SCENE_ROOM, 20000, 1);
  ASSERT_TRUE(sc.ok);
  const size_t room = sc.s.n, ball = 1200;
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (size_t i = 0; i < room; ++i)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], sc.s.xyz[3 * i + d]);
      hi[d] = std::max(hi[d], sc.s.xyz[3 * i + d]);
    }
  std::vector<float> xyz(sc.s.xyz, sc.s.xyz + 3 * room), truth(sc.s.normals,
                                                               sc.s.normals + 3 * room);
  const double golden = 2.399963229728653; // Fibonacci sphere: even spread
  for (size_t k = 0; k < ball; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / ball, r = std::sqrt(1.0 - z * z);
    const double u[3] = {r * std::cos(golden * k), r * std::sin(golden * k), z};
    for (int d = 0; d < 3; ++d) {
      const double c = d < 2 ? 0.5 * (lo[d] + hi[d]) : hi[2] + 0.6;
      xyz.push_back((float)(c + 0.3 * u[d]));
      truth.push_back((float)u[d]);
    }
  }
  const size_t n = room + ball;
  dacpo_params p = defaults();
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    p.seed = seed;
    std::vector<float> in(3 * n); // the truth with every second sign flipped
    for (size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d)
        in[3 * i + d] = (i % 2 ? -1.0f : 1.0f) * truth[3 * i + d];
    auto ctx = makeCtx();
    Result r = orient(ctx.get(), p, xyz.data(), std::move(in), n);
    ASSERT_EQ(r.status, DACPO_OK) << r.error;
    EXPECT_GE(r.stats.num_components, 2u);
    size_t room_right = 0, ball_right = 0;
    for (size_t i = 0; i < n; ++i) {
      const float* g = truth.data() + 3 * i;
      const float* o = r.normals.data() + 3 * i;
      const bool right = g[0] * o[0] + g[1] * o[1] + g[2] * o[2] > 0.0f;
      (i < room ? room_right : ball_right) += right;
    }
    const bool room_flipped = 2 * room_right < room;
    const size_t ball_out = room_flipped ? ball - ball_right : ball_right;
    printf("seed %llu: room %.2f %% right, ball %.2f %% outward in the room's frame\n",
           (unsigned long long)seed,
           100.0 * (room_flipped ? room - room_right : room_right) / room,
           100.0 * ball_out / ball);
    EXPECT_GE((double)ball_out, 0.95 * (double)ball);
  }
}

// Two rooms scanned apart: the open box and a copy of it 100 box sizes away,
// two components. Each room wraps around its own centroid with its normals
// facing in; in the box of the whole cloud each is small, and the closed-part
// rule turned the second one outward (0.00-0.03 % of it right, seeds 1-3). Measured
// after the rule took its size against the widest part: 100 % of both rooms
// right on seeds 1-3.
TEST(DacpoPipeline, TwoRoomsFarApartBothFaceIn)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 8000, 1);
  ASSERT_TRUE(sc.ok);
  const size_t room = sc.s.n, n = 2 * room;
  float lo = 1e30f, hi = -1e30f;
  for (size_t i = 0; i < room; ++i) {
    lo = std::min(lo, sc.s.xyz[3 * i]);
    hi = std::max(hi, sc.s.xyz[3 * i]);
  }
  std::vector<float> xyz(sc.s.xyz, sc.s.xyz + 3 * room), truth(sc.s.normals,
                                                               sc.s.normals + 3 * room);
  for (size_t i = 0; i < room; ++i)
    for (int d = 0; d < 3; ++d) {
      xyz.push_back(sc.s.xyz[3 * i + d] + (d == 0 ? 100.0f * (hi - lo) : 0.0f));
      truth.push_back(sc.s.normals[3 * i + d]);
    }
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    p.seed = seed;
    auto ctx = makeCtx();
    Result r = orient(ctx.get(), p, xyz.data(), std::vector<float>(3 * n, 0.0f), n);
    ASSERT_EQ(r.status, DACPO_OK) << r.error;
    EXPECT_EQ(r.stats.num_components, 2u);
    size_t right[2] = {0, 0};
    for (size_t i = 0; i < n; ++i) {
      const float* g = truth.data() + 3 * i;
      const float* o = r.normals.data() + 3 * i;
      right[i >= room] += g[0] * o[0] + g[1] * o[1] + g[2] * o[2] > 0.0f;
    }
    printf("seed %llu: first room %.2f %% right, second %.2f %%\n",
           (unsigned long long)seed,
           100.0 * right[0] / room,
           100.0 * right[1] / room);
    EXPECT_GE((double)right[0], 0.99 * (double)room);
    EXPECT_GE((double)right[1], 0.99 * (double)room);
  }
}

// Points in blocks whose majority is wrong under the sign that makes most points
// right: what a wrong block flip costs (as pcl_dacpo_eval's flip split counts).
double
wrongBlockPercent(const Scene& sc, const Result& r)
{
  const size_t n = sc.s.n;
  std::vector<size_t> right(r.stats.num_blocks, 0), size(r.stats.num_blocks, 0);
  size_t agree = 0;
  for (size_t i = 0; i < n; ++i) {
    const float* g = sc.s.normals + 3 * i;
    const float* o = r.normals.data() + 3 * i;
    const bool ok = g[0] * o[0] + g[1] * o[1] + g[2] * o[2] > 0.0f;
    agree += ok;
    if (r.block[i] >= 0) {
      size[r.block[i]]++;
      right[r.block[i]] += ok;
    }
  }
  const bool flip = 2 * agree < n;
  size_t wrong = 0;
  for (size_t b = 0; b < size.size(); ++b) {
    const size_t ok = flip ? size[b] - right[b] : right[b];
    if (2 * ok < size[b])
      wrong += size[b];
  }
  return 100.0 * static_cast<double>(wrong) / static_cast<double>(n);
}

// The side cue as an absolute sign in stage 5 (cue_anchor): on the generated
// 100K room (seed 2, estimated normals) the seams of a half-wrong block
// outvoted a bookcase block whose 1,400 cue points all said "as it is".
// Measured: blocks with a wrong majority hold 7.47 % of the points without the
// anchor (cue_anchor 0; 11.87 % wrong in all), 4.63 % with it (9.45 %); the rest
// is a thick partition (two blocks) both faces of which point inward, where the
// cue does not fire.
TEST(DacpoPipeline, SideCueAnchorsABlockTheSeamsVoteWrong)
{
  Scene sc(DACPO_SCENE_ROOM, 100000, 1);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 100000u);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  p.seed = 2;
  Result r = orientScene(sc, p);
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  ASSERT_EQ(r.block.size(), sc.s.n);
  const double flips = wrongBlockPercent(sc, r);
  RecordProperty("wrong_block_percent", std::to_string(flips));
  EXPECT_LT(flips, 5.5);
  EXPECT_LT(wrongPercent(sc, r), 10.5);
  EXPECT_GT(r.stats.cue_anchored_blocks, 0u);
  EXPECT_LE(r.stats.cue_anchored_blocks, r.stats.num_blocks);

  // Off: no block is anchored and no part follows the cue.
  p.cue_anchor = 0.0;
  Result off = orientScene(sc, p);
  ASSERT_EQ(off.status, DACPO_OK) << off.error;
  EXPECT_EQ(off.stats.cue_anchored_blocks, 0u);
  EXPECT_EQ(off.stats.parts_cue_signed, 0u);
}

// ---- published results --------------------------------------------------------

namespace {

// Two copies of the box, the second 100 m along x, in a fixed shuffled order:
// the points into xyz and their true normals into gt (both 3 * 2 * sc.s.n).
void
shuffledTwoBoxes(const Scene& sc, std::vector<float>& xyz, std::vector<float>& gt)
{
  const size_t half = sc.s.n, n = 2 * half;
  std::vector<size_t> perm(n);
  for (size_t i = 0; i < n; ++i)
    perm[i] = i;
  uint64_t st = 12345;
  for (size_t i = n - 1; i > 0; --i) { // Fisher-Yates with a fixed LCG
    st = st * 6364136223846793005ull + 1442695040888963407ull;
    std::swap(perm[i], perm[(st >> 33) % (i + 1)]);
  }
  for (size_t j = 0; j < n; ++j) {
    const size_t src = perm[j] % half;
    const float shift = perm[j] < half ? 0.0f : 100.0f;
    for (int a = 0; a < 3; ++a) {
      xyz[3 * j + a] = sc.s.xyz[3 * src + a] + (a == 0 ? shift : 0.0f);
      gt[3 * j + a] = sc.s.normals[3 * src + a];
    }
  }
}

// Checks the per-point block ids of the two boxes at xyz: valid, all used, none
// spanning components, spatially compact.
void
expectCompactBlocks(const Scene& sc, const Result& r, const std::vector<float>& xyz)
{
  const size_t half = sc.s.n, n = 2 * half;
  // blocks: valid ids, all used, none spanning components, spatially compact
  // (a scrambled order would give each block a random spread of points)
  const size_t nb = r.stats.num_blocks;
  std::vector<int32_t> block_comp(nb, -1);
  std::vector<double> sum(3 * nb, 0.0), sum2(nb, 0.0);
  std::vector<size_t> cnt(nb, 0);
  for (size_t j = 0; j < n; ++j) {
    const int32_t b = r.block[j];
    ASSERT_GE(b, 0);
    ASSERT_LT(static_cast<size_t>(b), nb);
    if (block_comp[b] < 0)
      block_comp[b] = r.component[j];
    EXPECT_EQ(block_comp[b], r.component[j]) << "block " << b << " spans components";
    cnt[b]++;
    for (int a = 0; a < 3; ++a) {
      sum[3 * b + a] += xyz[3 * j + a];
      sum2[b] += double(xyz[3 * j + a]) * xyz[3 * j + a];
    }
  }
  double within = 0.0;
  for (size_t b = 0; b < nb; ++b) {
    ASSERT_GT(cnt[b], 0u) << "block " << b << " is empty";
    double m2 = 0.0;
    for (int a = 0; a < 3; ++a)
      m2 += sum[3 * b + a] * sum[3 * b + a] / double(cnt[b]);
    within += sum2[b] - m2;
  }
  // Spread of the points about their box's centre (both boxes): blocks in a
  // scrambled order would keep nearly all of it (ratio ~1); measured 0.53.
  double box_spread = 0.0;
  {
    double s1[3] = {0, 0, 0}, s2 = 0.0;
    for (size_t i = 0; i < half; ++i)
      for (int a = 0; a < 3; ++a) {
        s1[a] += sc.s.xyz[3 * i + a];
        s2 += double(sc.s.xyz[3 * i + a]) * sc.s.xyz[3 * i + a];
      }
    box_spread =
        2.0 * (s2 - (s1[0] * s1[0] + s1[1] * s1[1] + s1[2] * s1[2]) / double(half));
  }
  EXPECT_GE(nb, 4u);
  EXPECT_LT(within, 0.75 * box_spread) << "blocks are not spatially compact";
}

// Checks the per-point curvature of the two boxes at xyz: ~0 on the faces away
// from the creases, clearly > 0 on them.
void
expectCurvatureOnCreases(const Result& r, const std::vector<float>& xyz)
{
  const size_t n = xyz.size() / 3;
  // curvature: ~0 on the faces away from the creases, clearly > 0 on them
  const double planes[5][2] = {{0, 0.0}, {0, 4.0}, {1, 0.0}, {1, 3.0}, {2, 0.0}};
  double crease_sum = 0.0;
  size_t crease_n = 0, flat_n = 0;
  for (size_t j = 0; j < n; ++j) {
    const float x[3] = {xyz[3 * j] - (xyz[3 * j] > 50.0f ? 100.0f : 0.0f),
                        xyz[3 * j + 1],
                        xyz[3 * j + 2]};
    // distance to the second-closest of the five box planes
    double d[5];
    for (int k = 0; k < 5; ++k)
      d[k] = std::fabs(x[static_cast<int>(planes[k][0])] - planes[k][1]);
    std::sort(d, d + 5);
    ASSERT_TRUE(std::isfinite(r.curvature[j])) << j;
    if (d[1] > 0.4) {
      EXPECT_LT(r.curvature[j], 1e-4f) << "flat point " << j;
      ++flat_n;
    }
    else if (d[1] < 0.02) {
      crease_sum += r.curvature[j];
      ++crease_n;
    }
  }
  ASSERT_GT(flat_n, n / 2);
  ASSERT_GT(crease_n, 20u);
  EXPECT_GT(crease_sum / double(crease_n), 0.02); // measured 0.083
}

} // namespace

// Two copies of the box, 100 m apart, in a shuffled input order: every
// per-point array must follow the input order. Each box is oriented on its
// own (DACPO_DISCONNECTED_SEPARATE): under the viewpoint policy the second
// open box is a part that wraps around its centroid, which the closed-part
// rule turns outward (docs/DESIGN.md, "Known limits"), and that rule is not
// what this test is about.
TEST(DacpoPipeline, PerPointOutputsFollowInputOrder)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 8000, 2);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 8000u);
  const size_t half = sc.s.n, n = 2 * half;
  std::vector<float> xyz(3 * n), gt(3 * n);
  shuffledTwoBoxes(sc, xyz, gt);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  p.disconnected = DACPO_DISCONNECTED_SEPARATE;
  auto ctx = makeCtx();
  Result r = orient(ctx.get(), p, xyz.data(), std::vector<float>(3 * n, 0.0f), n);
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  ASSERT_EQ(r.stats.input_points, n);
  ASSERT_EQ(r.stats.num_components, 2u);
  ASSERT_EQ(r.component.size(), n);
  ASSERT_EQ(r.block.size(), n);
  ASSERT_EQ(r.curvature.size(), n);

  // components: ids in order of first input point, so point 0's is 0
  const bool first_far = xyz[0] > 50.0f;
  for (size_t j = 0; j < n; ++j)
    ASSERT_EQ(r.component[j], (xyz[3 * j] > 50.0f) != first_far ? 1 : 0) << j;
  // each box oriented on its own, one free sign per component
  EXPECT_LT(
      dacpo_score_oriented(gt.data(), r.normals.data(), n, r.component.data(), nullptr),
      1.0);

  ASSERT_NO_FATAL_FAILURE(expectCompactBlocks(sc, r, xyz));

  ASSERT_NO_FATAL_FAILURE(expectCurvatureOnCreases(r, xyz));
}

TEST(DacpoPipeline, BlockFlipsAndEdgesAreConsistent)
{
  Scene sc(DACPO_SCENE_TWO_ROOMS, 20000, 3);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 20000u);
  dacpo_params p = defaults();
  p.ipsr_enabled = 0; // VCR weights still get one Poisson mesh per block
  Result r = orientScene(sc, p);
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  const dacpo_stats& st = r.stats;
  ASSERT_GE(st.num_blocks, 4u);
  ASSERT_EQ(r.flips.size(), st.num_blocks);
  size_t flipped = 0;
  for (uint8_t f : r.flips) {
    EXPECT_LE(f, 1u);
    flipped += f != 0;
  }
  EXPECT_EQ(st.flipped_blocks, flipped);

  ASSERT_GE(st.num_block_edges, st.num_blocks - 1)
      << "one component needs a spanning graph";
  ASSERT_EQ(r.edges.size(), st.num_block_edges);
  std::set<std::pair<int32_t, int32_t>> pairs;
  size_t zero = 0;
  for (const dacpo_edge_info& e : r.edges) {
    EXPECT_GE(e.block_a, 0);
    EXPECT_LT(e.block_a, e.block_b);
    EXPECT_LT(static_cast<size_t>(e.block_b), st.num_blocks);
    EXPECT_TRUE(pairs.insert({e.block_a, e.block_b}).second) << "repeated edge";
    EXPECT_TRUE(std::isfinite(e.alpha));
    EXPECT_TRUE(std::isfinite(e.alpha_bar));
    EXPECT_GE(e.alpha, 0.0);
    EXPECT_GE(e.alpha_bar, 0.0);
    EXPECT_GE(e.confidence, 0.0);
    EXPECT_LE(e.confidence, 1.0);
    zero += e.alpha == 0.0 && e.alpha_bar == 0.0;
  }
  EXPECT_EQ(st.zero_weight_edges, zero);
  // block ids of the points index the flips array
  for (int32_t b : r.block)
    ASSERT_LT(static_cast<size_t>(b), r.flips.size());
  EXPECT_EQ(st.input_points, sc.s.n);
  EXPECT_EQ(st.unique_points + st.duplicate_points, st.input_points);
  EXPECT_LE(st.largest_component, st.unique_points);
  EXPECT_GT(st.peak_block_points, 0u);
  EXPECT_EQ(st.ipsr_iterations_total, 0u);
}

TEST(DacpoPipeline, StageTimesAddUp)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 1);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 10000u);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  Result r = orientScene(sc, p);
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  double sum = 0.0;
  for (int s = 0; s < DACPO_STAGE_COUNT; ++s) {
    EXPECT_GE(r.stats.stage_seconds[s], 0.0)
        << dacpo_stage_name(static_cast<dacpo_stage>(s));
    sum += r.stats.stage_seconds[s];
  }
  EXPECT_GT(r.stats.total_seconds, 0.0);
  EXPECT_LE(sum, r.stats.total_seconds + 1e-3);
  // iPSR ran and its share of the stage 2-3 pass is reported
  EXPECT_GT(r.stats.ipsr_iterations_total, 0u);
  EXPECT_GE(r.stats.ipsr_iterations_total, r.stats.ipsr_iterations_max);
  EXPECT_LE(r.stats.ipsr_iterations_max, p.ipsr_max_iterations);
  EXPECT_GT(r.stats.stage_seconds[DACPO_STAGE_IPSR], 0.0);
  // the work profile: every block ran between 4 (the first four agreed) and
  // all restarts of stage 2; stage 3 voted faces, and no more iterations kept
  // their surface than ran
  const size_t nb = r.stats.num_blocks;
  ASSERT_GT(nb, 0u);
  EXPECT_GE(r.stats.dipole_restarts_total, 4 * nb);
  EXPECT_LE(r.stats.dipole_restarts_total, p.dipole_restarts * nb);
  EXPECT_LE(r.stats.dipole_blocks_all_restarts, nb);
  EXPECT_EQ(r.stats.dipole_restarts_total,
            4 * nb + (p.dipole_restarts - 4) * r.stats.dipole_blocks_all_restarts);
  EXPECT_GT(r.stats.ipsr_faces_total, 0u);
  EXPECT_GE(r.stats.ipsr_cg_iterations_total, 1u);
  EXPECT_LE(r.stats.ipsr_surfaces_reused, r.stats.ipsr_iterations_total);
}

// ---- determinism ----------------------------------------------------------------

TEST(DacpoPipeline, SameSeedIsBitIdentical)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 4);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 10000u);
  dacpo_params p = defaults();
  p.seed = 42;
  auto ctx = makeCtx();
  // the second run reuses the context, the third gets a fresh one
  Result a = orient(ctx.get(), p, sc.s.xyz, scrambled(sc, 9), sc.s.n);
  Result b = orient(ctx.get(), p, sc.s.xyz, scrambled(sc, 9), sc.s.n);
  Result c = orientScene(sc, p); // scrambled with another seed: same axes
  ASSERT_EQ(a.status, DACPO_OK) << a.error;
  ASSERT_EQ(b.status, DACPO_OK) << b.error;
  ASSERT_EQ(c.status, DACPO_OK) << c.error;
  EXPECT_TRUE(sameBits(a.normals, b.normals));
  EXPECT_EQ(a.block, b.block);
  EXPECT_EQ(a.flips, b.flips);
  // The given signs are ignored: a different scramble gives the same result.
  EXPECT_TRUE(sameBits(a.normals, c.normals));
}

TEST(DacpoPipeline, ThreadCountDoesNotChangeResult)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 5);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 10000u);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  p.num_threads = 1;
  Result one = orientScene(sc, p);
  p.num_threads = 2;
  Result two = orientScene(sc, p);
  expectSameRun(one, two);
  EXPECT_TRUE(sameBits(one.curvature, two.curvature));
}

TEST(DacpoPipeline, CallerSearchMatchesBuiltIn)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 4000, 6);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 4000u);
  BruteForce bf{sc.s.xyz, sc.s.n};
  dacpo_search search = {bruteForceKnn, &bf};
  for (int estimate : {0, 1}) {
    SCOPED_TRACE(estimate ? "estimated normals" : "given normals");
    dacpo_params p = defaults();
    p.estimate_normals = estimate;
    p.num_threads = 2; // the callback is reentrant
    Result builtin = orientScene(sc, p);
    Result caller = orientScene(sc, p, &search);
    ASSERT_EQ(builtin.status, DACPO_OK) << builtin.error;
    ASSERT_EQ(caller.status, DACPO_OK) << caller.error;
    ASSERT_EQ(builtin.stats.duplicate_points, 0u);
    EXPECT_TRUE(sameBits(builtin.normals, caller.normals));
    EXPECT_EQ(builtin.block, caller.block);
    EXPECT_EQ(builtin.flips, caller.flips);
    EXPECT_TRUE(sameBits(builtin.curvature, caller.curvature));
    EXPECT_LT(wrongPercent(sc, caller), 1.0);
  }
}

// ---- options
// -------------------------------------------------------------------------

// Measured: 0.000 % wrong for every combination below (10K points, given and
// estimated normals).
TEST(DacpoPipeline, EdgeWeightsAndIpsrAllSucceed)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 1);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 10000u);
  for (dacpo_edge_weight w :
       {DACPO_WEIGHT_VCR, DACPO_WEIGHT_DIPOLE_BOUNDARY, DACPO_WEIGHT_OVERLAP}) {
    for (int ipsr : {0, 1}) {
      SCOPED_TRACE("edge_weight " + std::to_string(static_cast<int>(w)) + ", ipsr " +
                   std::to_string(ipsr));
      dacpo_params p = defaults();
      p.edge_weight = w;
      p.ipsr_enabled = ipsr;
      Result r = orientScene(sc, p);
      ASSERT_EQ(r.status, DACPO_OK) << r.error;
      EXPECT_LT(wrongPercent(sc, r), 2.0);
      EXPECT_EQ(r.stats.ipsr_iterations_total > 0, ipsr == 1);
      EXPECT_EQ(r.edges.size(), r.stats.num_block_edges);
    }
  }
}

// ---- callbacks
// -----------------------------------------------------------------------

TEST(DacpoPipeline, ProgressStagesAreOrdered)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 1);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 10000u);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  p.num_threads = 2;
  ProgressLog log;
  dacpo_progress prog = {logProgress, &log};
  Result r = orientScene(sc, p, nullptr, &prog);
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  ASSERT_GE(log.calls.size(), 2u);
  EXPECT_EQ(log.off_thread, 0u) << "progress must arrive on the calling thread";
  EXPECT_EQ(log.calls.front().first, DACPO_STAGE_INPUT);
  EXPECT_EQ(log.calls.back().first, DACPO_STAGE_ILP);
  EXPECT_EQ(log.calls.back().second, 1.0);
  std::set<int> seen;
  for (size_t i = 0; i < log.calls.size(); ++i) {
    const int stage = log.calls[i].first;
    const double f = log.calls[i].second;
    EXPECT_GE(stage, 0);
    EXPECT_LT(stage, DACPO_STAGE_COUNT);
    EXPECT_GE(f, 0.0) << i;
    EXPECT_LE(f, 1.0) << i;
    if (i > 0) {
      EXPECT_GE(stage, log.calls[i - 1].first) << "stage went back at call " << i;
    }
    seen.insert(stage);
  }
  for (int s : {DACPO_STAGE_NEIGHBORS,
                DACPO_STAGE_NORMALS,
                DACPO_STAGE_SEGMENT,
                DACPO_STAGE_IPSR,
                DACPO_STAGE_EDGE_WEIGHTS})
    EXPECT_EQ(seen.count(s), 1u) << dacpo_stage_name(static_cast<dacpo_stage>(s));
}

// ---- output form
// ------------------------------------------------------------------------

TEST(DacpoPipeline, OutputKeepsTheGivenAxis)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 7);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 10000u);
  const size_t n = sc.s.n;
  // Given axes: ground truth tilted a little, any length, random sign. The
  // output must be the given axis, normalized, only its sign chosen.
  std::vector<float> given = scrambled(sc, 11);
  uint64_t st = 99;
  for (size_t i = 0; i < n; ++i) {
    st = st * 6364136223846793005ull + 1442695040888963407ull;
    const float scale =
        0.01f + 10.0f * static_cast<float>((st >> 40) & 0xFFFF) / 65536.0f;
    const float tilt =
        0.2f * (static_cast<float>((st >> 20) & 0xFFFF) / 65536.0f - 0.5f);
    given[3 * i] = scale * (given[3 * i] + tilt);
    given[3 * i + 1] = scale * (given[3 * i + 1] - tilt);
    given[3 * i + 2] = scale * (given[3 * i + 2] + 0.5f * tilt);
  }
  auto ctx = makeCtx();
  Result r = orient(ctx.get(), defaults(), sc.s.xyz, given, n);
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  size_t bad_len = 0, bad_axis = 0;
  for (size_t i = 0; i < n; ++i) {
    double g[3], len2 = 0.0, glen = 0.0, dot = 0.0;
    for (int a = 0; a < 3; ++a) {
      g[a] = given[3 * i + a];
      glen += g[a] * g[a];
    }
    glen = std::sqrt(glen);
    for (int a = 0; a < 3; ++a) {
      const double o = r.normals[3 * i + a];
      len2 += o * o;
      dot += o * g[a] / glen;
    }
    bad_len += std::fabs(std::sqrt(len2) - 1.0) > 1e-6;
    bad_axis += std::fabs(std::fabs(dot) - 1.0) > 1e-6;
  }
  EXPECT_EQ(bad_len, 0u);
  EXPECT_EQ(bad_axis, 0u);
  // tilted axes do not change which way they point
  EXPECT_LT(wrongPercent(sc, r), 1.0);
}

// keep_mesh: the blocks' trimmed iPSR meshes come back as one mesh whose faces are
// wound like the output normals (flipped blocks re-wound), near the samples.
TEST(DacpoPipeline, KeptMeshAgreesWithOutputNormals)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 8000, 3);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 8000u);
  dacpo_params p = defaults();
  p.keep_mesh = 1;
  auto ctx = makeCtx();
  Result r = orient(ctx.get(), p, sc.s.xyz, scrambled(sc, 7), sc.s.n);
  ASSERT_EQ(r.status, DACPO_OK) << r.error;
  ASSERT_GT(r.stats.flipped_blocks, 0u) << "the test should cover re-wound blocks";
  const float* v = nullptr;
  const int32_t* t = nullptr;
  size_t nv = 0;
  const size_t nt = dacpo_ctx_mesh(ctx.get(), &v, &nv, &t);
  ASSERT_GT(nt, 1000u);
  ASSERT_GT(nv, 500u);
  // Every 37th face: its normal against the output normal of the nearest sample.
  size_t agree = 0, checked = 0;
  for (size_t f = 0; f < nt; f += 37, ++checked) {
    const float* a = v + 3 * t[3 * f];
    const float* b = v + 3 * t[3 * f + 1];
    const float* c = v + 3 * t[3 * f + 2];
    for (int k = 0; k < 3; ++k) {
      ASSERT_GE(t[3 * f + k], 0);
      ASSERT_LT(static_cast<size_t>(t[3 * f + k]), nv);
    }
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double fn[3] = {e1[1] * e2[2] - e1[2] * e2[1],
                          e1[2] * e2[0] - e1[0] * e2[2],
                          e1[0] * e2[1] - e1[1] * e2[0]};
    const double m[3] = {
        (a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3};
    size_t best = 0;
    double bestd = 1e300;
    for (size_t i = 0; i < sc.s.n; ++i) {
      const float* q = sc.s.xyz + 3 * i;
      const double d = (q[0] - m[0]) * (q[0] - m[0]) + (q[1] - m[1]) * (q[1] - m[1]) +
                       (q[2] - m[2]) * (q[2] - m[2]);
      if (d < bestd) {
        bestd = d;
        best = i;
      }
    }
    const float* on = r.normals.data() + 3 * best;
    agree += fn[0] * on[0] + fn[1] * on[1] + fn[2] * on[2] > 0.0;
  }
  RecordProperty("agreeing_faces",
                 std::to_string(agree) + "/" + std::to_string(checked));
  EXPECT_GT(static_cast<double>(agree), 0.95 * static_cast<double>(checked));

  // Without keep_mesh there is no mesh.
  dacpo_params q = defaults();
  Result r2 = orient(ctx.get(), q, sc.s.xyz, scrambled(sc, 7), sc.s.n);
  ASSERT_EQ(r2.status, DACPO_OK);
  EXPECT_EQ(dacpo_ctx_mesh(ctx.get(), nullptr, nullptr, nullptr), 0u);
}

// Keeping the mesh must not change the edge measure the caller asked for: with
// keep_mesh the blocks have meshes, which once made every measure VCR.
TEST(DacpoPipeline, KeepingTheMeshKeepsTheEdgeWeightMeasure)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 8000, 3);
  ASSERT_TRUE(sc.ok);
  ASSERT_EQ(sc.s.n, 8000u);
  for (dacpo_edge_weight w : {DACPO_WEIGHT_DIPOLE_BOUNDARY, DACPO_WEIGHT_OVERLAP}) {
    std::vector<std::vector<double>> alpha(2);
    for (int keep = 0; keep < 2; ++keep) {
      dacpo_params p = defaults();
      p.edge_weight = w;
      p.keep_mesh = keep;
      auto ctx = makeCtx();
      Result r = orient(ctx.get(), p, sc.s.xyz, scrambled(sc, 7), sc.s.n);
      ASSERT_EQ(r.status, DACPO_OK) << r.error;
      const dacpo_edge_info* e = dacpo_ctx_edges(ctx.get());
      ASSERT_GT(r.stats.num_block_edges, 0u);
      for (size_t k = 0; k < r.stats.num_block_edges; ++k)
        alpha[keep].push_back(e[k].alpha);
      if (keep)
        EXPECT_GT(dacpo_ctx_mesh(ctx.get(), nullptr, nullptr, nullptr), 0u);
    }
    EXPECT_EQ(alpha[0], alpha[1]) << "edge weight " << static_cast<int>(w);
  }
}

// ---- the run as work units (dacpo_advanced.h) ------------------------------

struct JobDeleter {
  void
  operator()(dacpo_job* j) const
  {
    dacpo_job_free(j);
  }
};
using JobPtr = std::unique_ptr<dacpo_job, JobDeleter>;

struct UnitBytes {
  void* p = nullptr;
  size_t size = 0;
  ~UnitBytes() { dacpo_unit_bytes_free(p); }
};

// Block b as another process runs it: task bytes out, result bytes back.
dacpo_status
blockAsBytes(dacpo_job* job, size_t b)
{
  char msg[256];
  UnitBytes task, result;
  dacpo_status st = dacpo_job_block_task(job, b, &task.p, &task.size, msg, sizeof(msg));
  if (st == DACPO_OK)
    st = dacpo_block_task_run(
        task.p, task.size, &result.p, &result.size, msg, sizeof(msg));
  if (st == DACPO_OK)
    st = dacpo_job_put_block(job, result.p, result.size, msg, sizeof(msg));
  EXPECT_EQ(st, DACPO_OK) << msg;
  return st;
}

dacpo_status
edgeAsBytes(dacpo_job* job, size_t e)
{
  char msg[256];
  UnitBytes task;
  double alpha = -1.0, alpha_bar = -1.0;
  dacpo_status st = dacpo_job_edge_task(job, e, &task.p, &task.size, msg, sizeof(msg));
  if (st == DACPO_OK)
    st = dacpo_edge_task_run(task.p, task.size, &alpha, &alpha_bar, msg, sizeof(msg));
  if (st == DACPO_OK)
    st = dacpo_job_put_edge(job, e, alpha, alpha_bar, msg, sizeof(msg));
  EXPECT_EQ(st, DACPO_OK) << msg;
  return st;
}

enum class UnitOrder { Reversed, TwoThreads, AsBytes };

// dacpo_orient()'s steps called one by one: blocks and edges last to first,
// split between two threads (even and odd ids), or last to first as bytes
// (task -> run without the job -> put), as another process would run them.
Result
orientByUnits(const Scene& sc, const dacpo_params& p, UnitOrder order)
{
  auto ctx = makeCtx();
  Result r;
  std::vector<float> normals(3 * sc.s.n, 0.0f);
  dacpo_job* raw = nullptr;
  r.status = dacpo_job_create(
      ctx.get(), &p, nullptr, nullptr, sc.s.xyz, nullptr, sc.s.n, &raw);
  JobPtr job(raw);
  if (r.status != DACPO_OK) {
    collect(ctx.get(), r);
    return r;
  }
  auto run_units = [&](size_t count, auto unit) {
    std::vector<dacpo_status> st(count, DACPO_OK);
    if (order == UnitOrder::Reversed) {
      for (size_t i = count; i-- > 0;)
        st[i] = unit(i);
    }
    else {
      std::thread odd([&] {
        for (size_t i = 1; i < count; i += 2)
          st[i] = unit(i);
      });
      for (size_t i = 0; i < count; i += 2)
        st[i] = unit(i);
      odd.join();
    }
    for (dacpo_status s : st)
      if (s != DACPO_OK)
        return s;
    return DACPO_OK;
  };
  char msg[256];
  r.status = run_units(dacpo_job_num_blocks(job.get()), [&](size_t b) {
    return order == UnitOrder::AsBytes
               ? blockAsBytes(job.get(), b)
               : dacpo_job_orient_block(job.get(), b, nullptr, 0);
  });
  if (r.status == DACPO_OK && p.edge_weight == DACPO_WEIGHT_VCR)
    r.status = run_units(dacpo_job_num_edges(job.get()), [&](size_t e) {
      return order == UnitOrder::AsBytes
                 ? edgeAsBytes(job.get(), e)
                 : dacpo_job_weigh_edge(job.get(), e, nullptr, 0);
    });
  else if (r.status == DACPO_OK) {
    // edge by edge is for VCR only; the other measures weigh all edges at once
    if (dacpo_job_num_edges(job.get()) > 0) {
      EXPECT_EQ(dacpo_job_weigh_edge(job.get(), 0, msg, sizeof(msg)),
                DACPO_ERR_INVALID_ARGUMENT);
      EXPECT_NE(std::string(msg).find("dacpo_job_weigh_edges"), std::string::npos)
          << msg;
    }
    r.status = dacpo_job_weigh_edges(job.get());
  }
  if (r.status == DACPO_OK)
    r.status = dacpo_job_solve(job.get());
  if (r.status == DACPO_OK)
    r.status = dacpo_job_finish(job.get(), normals.data());
  r.normals = std::move(normals);
  collect(ctx.get(), r);
  return r;
}

TEST(DacpoJob, UnitsInAnyOrderGiveTheAnswerOfOrient)
{
  Scene sc(DACPO_SCENE_ROOM, 12000, 3);
  ASSERT_TRUE(sc.ok);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  p.num_blocks = 12;
  Result whole = orientScene(sc, p);
  ASSERT_GT(whole.stats.num_block_edges, 10u);
  expectSameRun(whole, orientByUnits(sc, p, UnitOrder::Reversed));
  expectSameRun(whole, orientByUnits(sc, p, UnitOrder::TwoThreads));
  expectSameRun(whole, orientByUnits(sc, p, UnitOrder::AsBytes));
  EXPECT_LT(wrongPercent(sc, whole), 15.0);
}

TEST(DacpoJob, OtherEdgeMeasuresWeighAllEdgesAtOnce)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 6000, 2);
  ASSERT_TRUE(sc.ok);
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  p.num_blocks = 8;
  for (dacpo_edge_weight w : {DACPO_WEIGHT_DIPOLE_BOUNDARY, DACPO_WEIGHT_OVERLAP}) {
    p.edge_weight = w;
    expectSameRun(orientScene(sc, p), orientByUnits(sc, p, UnitOrder::Reversed));
  }
  // blocks as bytes carry their ring normals (overlap weights) and no mesh
  p.edge_weight = DACPO_WEIGHT_OVERLAP;
  expectSameRun(orientScene(sc, p), orientByUnits(sc, p, UnitOrder::AsBytes));
}

namespace {

// Block 0's task and result bytes: the size query, a task cut short, altered or
// with a NaN point is not run, and a result that is cut short, longer, for
// another block or put twice is refused.
void
expectBlockBytesChecked(dacpo_job* raw,
                        char (&msg)[256],
                        UnitBytes& task,
                        UnitBytes& result,
                        UnitBytes& other,
                        size_t& asked)
{
  ASSERT_EQ(dacpo_job_block_task(raw, 0, &task.p, &task.size, msg, sizeof(msg)),
            DACPO_OK);
  // bytes NULL: the size alone
  ASSERT_EQ(dacpo_job_block_task(raw, 0, nullptr, &asked, msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(asked, task.size);
  EXPECT_EQ(dacpo_job_block_task(raw, 0, nullptr, nullptr, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_job_block_task(raw, 99, &other.p, &other.size, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(other.p, nullptr);
  // a task cut short or with another magic is not run
  void* out = nullptr;
  size_t out_size = 0;
  EXPECT_EQ(
      dacpo_block_task_run(task.p, task.size - 8, &out, &out_size, msg, sizeof(msg)),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("bytes"), std::string::npos) << msg;
  EXPECT_EQ(out, nullptr);
  std::vector<unsigned char> bad(static_cast<unsigned char*>(task.p),
                                 static_cast<unsigned char*>(task.p) + task.size);
  bad[0] ^= 0xff;
  EXPECT_EQ(
      dacpo_block_task_run(bad.data(), bad.size(), &out, &out_size, msg, sizeof(msg)),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("no block task"), std::string::npos) << msg;
  EXPECT_EQ(dacpo_block_task_run(nullptr, 0, &out, &out_size, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  // the last axis's z (the task's last 8 bytes) made NaN
  std::vector<unsigned char> nan_point(static_cast<unsigned char*>(task.p),
                                       static_cast<unsigned char*>(task.p) + task.size);
  const double nan = std::nan("");
  std::memcpy(nan_point.data() + task.size - 8, &nan, sizeof(nan));
  EXPECT_EQ(dacpo_block_task_run(
                nan_point.data(), nan_point.size(), &out, &out_size, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("not finite"), std::string::npos) << msg;
  ASSERT_EQ(dacpo_block_task_run(
                task.p, task.size, &result.p, &result.size, msg, sizeof(msg)),
            DACPO_OK)
      << msg;
  // a result is not a task, a truncated result or one with bytes after it is refused
  EXPECT_EQ(
      dacpo_block_task_run(result.p, result.size, &out, &out_size, msg, sizeof(msg)),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_job_put_block(raw, result.p, result.size - 1, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  std::vector<unsigned char> longer(static_cast<unsigned char*>(result.p),
                                    static_cast<unsigned char*>(result.p) +
                                        result.size);
  longer.push_back(0);
  EXPECT_EQ(dacpo_job_put_block(raw, longer.data(), longer.size(), msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("after the block result"), std::string::npos) << msg;
  // block 0's result claimed for block 1: its point count does not fit
  std::vector<unsigned char> renamed(static_cast<unsigned char*>(result.p),
                                     static_cast<unsigned char*>(result.p) +
                                         result.size);
  const uint64_t one = 1;
  std::memcpy(renamed.data() + 8, &one, sizeof(one));
  EXPECT_EQ(dacpo_job_put_block(raw, renamed.data(), renamed.size(), msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("block 1"), std::string::npos) << msg;
  ASSERT_EQ(dacpo_job_put_block(raw, result.p, result.size, msg, sizeof(msg)), DACPO_OK)
      << msg;
  EXPECT_EQ(dacpo_job_put_block(raw, result.p, result.size, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("already"), std::string::npos) << msg;
}

// Edge 0's task bytes: the size query, a task cut short or a block task is not
// run, and a NaN, negative or repeated put of its weights is refused.
void
expectEdgeBytesChecked(dacpo_job* raw,
                       char (&msg)[256],
                       const UnitBytes& task,
                       UnitBytes& edge,
                       size_t& asked)
{
  ASSERT_EQ(dacpo_job_edge_task(raw, 0, &edge.p, &edge.size, msg, sizeof(msg)),
            DACPO_OK)
      << msg;
  ASSERT_EQ(dacpo_job_edge_task(raw, 0, nullptr, &asked, msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(asked, edge.size);
  double alpha = 0.0, alpha_bar = 0.0;
  EXPECT_EQ(
      dacpo_edge_task_run(edge.p, edge.size - 4, &alpha, &alpha_bar, msg, sizeof(msg)),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(
      dacpo_edge_task_run(task.p, task.size, &alpha, &alpha_bar, msg, sizeof(msg)),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("no edge task"), std::string::npos) << msg;
  ASSERT_EQ(
      dacpo_edge_task_run(edge.p, edge.size, &alpha, &alpha_bar, msg, sizeof(msg)),
      DACPO_OK)
      << msg;
  EXPECT_EQ(dacpo_job_put_edge(raw, 0, std::nan(""), alpha_bar, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_job_put_edge(raw, 0, -1.0, alpha_bar, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  ASSERT_EQ(dacpo_job_put_edge(raw, 0, alpha, alpha_bar, msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(dacpo_job_put_edge(raw, 0, alpha, alpha_bar, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
}

} // namespace

// A message that is cut short, altered, for another block or sent twice is
// refused with a message; the job stays usable and completes.
TEST(DacpoJob, UnitBytesAreCheckedBeforeUse)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 3000, 1);
  ASSERT_TRUE(sc.ok);
  auto ctx = makeCtx();
  dacpo_params p = defaults();
  p.estimate_normals = 1;
  p.num_blocks = 4;
  dacpo_job* raw = nullptr;
  ASSERT_EQ(
      dacpo_job_create(ctx.get(), &p, nullptr, nullptr, sc.s.xyz, nullptr, 3000, &raw),
      DACPO_OK);
  JobPtr job(raw);
  ASSERT_GE(dacpo_job_num_blocks(raw), 2u);
  char msg[256];
  UnitBytes task, result, other;
  size_t asked = 0; // the task sizes asked with bytes NULL
  ASSERT_NO_FATAL_FAILURE(
      expectBlockBytesChecked(raw, msg, task, result, other, asked));
  for (size_t b = 1; b < dacpo_job_num_blocks(raw); ++b)
    ASSERT_EQ(dacpo_job_orient_block(raw, b, msg, sizeof(msg)), DACPO_OK) << msg;
  ASSERT_GT(dacpo_job_num_edges(raw), 0u);
  UnitBytes edge;
  ASSERT_NO_FATAL_FAILURE(expectEdgeBytesChecked(raw, msg, task, edge, asked));
  for (size_t e = 1; e < dacpo_job_num_edges(raw); ++e)
    ASSERT_EQ(dacpo_job_weigh_edge(raw, e, msg, sizeof(msg)), DACPO_OK) << msg;
  ASSERT_EQ(dacpo_job_solve(raw), DACPO_OK) << dacpo_ctx_last_error(ctx.get());
  std::vector<float> normals(3 * 3000);
  ASSERT_EQ(dacpo_job_finish(raw, normals.data()), DACPO_OK);
  dacpo_unit_bytes_free(nullptr);
}

TEST(DacpoJob, BadArgumentsAreRejectedWithAMessage)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 2000, 1);
  ASSERT_TRUE(sc.ok);
  auto ctx = makeCtx();
  dacpo_params p = defaults();
  dacpo_job* job = reinterpret_cast<dacpo_job*>(&p); // must be overwritten
  EXPECT_EQ(
      dacpo_job_create(nullptr, &p, nullptr, nullptr, sc.s.xyz, nullptr, 2000, &job),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_job_create(
                ctx.get(), &p, nullptr, nullptr, sc.s.xyz, nullptr, 2000, nullptr),
            DACPO_ERR_INVALID_ARGUMENT);
  // given axes expected (estimate_normals 0) but none given
  EXPECT_EQ(
      dacpo_job_create(ctx.get(), &p, nullptr, nullptr, sc.s.xyz, nullptr, 2000, &job),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(job, nullptr);
  EXPECT_NE(std::string(dacpo_ctx_last_error(ctx.get())).find("estimate_normals"),
            std::string::npos);
  EXPECT_EQ(
      dacpo_job_create(ctx.get(), &p, nullptr, nullptr, sc.s.xyz, nullptr, 0, &job),
      DACPO_ERR_EMPTY_INPUT);
  EXPECT_EQ(job, nullptr);

  p.estimate_normals = 1;
  p.num_blocks = 6;
  ASSERT_EQ(
      dacpo_job_create(ctx.get(), &p, nullptr, nullptr, sc.s.xyz, nullptr, 2000, &job),
      DACPO_OK)
      << dacpo_ctx_last_error(ctx.get());
  JobPtr hold(job);
  const size_t nb = dacpo_job_num_blocks(job), ne = dacpo_job_num_edges(job);
  ASSERT_GT(nb, 0u);
  char msg[128] = "unchanged";
  EXPECT_EQ(dacpo_job_orient_block(job, nb, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("block"), std::string::npos) << msg;
  EXPECT_EQ(dacpo_job_weigh_edge(job, ne, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("edge"), std::string::npos) << msg;
  size_t a = 0, b = 0;
  EXPECT_EQ(dacpo_job_edge_blocks(job, ne, &a, &b), DACPO_ERR_INVALID_ARGUMENT);
  for (size_t e = 0; e < ne; ++e) {
    ASSERT_EQ(dacpo_job_edge_blocks(job, e, &a, &b), DACPO_OK);
    EXPECT_LT(a, nb);
    EXPECT_LT(b, nb);
    EXPECT_NE(a, b);
  }
  EXPECT_EQ(dacpo_job_orient_block(job, 0, msg, sizeof(msg)), DACPO_OK);
  EXPECT_STREQ(msg, "");
  // out of order: a block twice, an edge before its blocks, the solve or the
  // finish too early
  EXPECT_EQ(dacpo_job_orient_block(job, 0, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("already"), std::string::npos) << msg;
  ASSERT_GT(ne, 0u);
  EXPECT_EQ(dacpo_job_weigh_edge(job, 0, msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("before its blocks"), std::string::npos) << msg;
  EXPECT_EQ(dacpo_job_solve(job), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(dacpo_ctx_last_error(ctx.get())).find("before block 1"),
            std::string::npos)
      << dacpo_ctx_last_error(ctx.get());
  std::vector<float> out(3 * 2000);
  EXPECT_EQ(dacpo_job_finish(job, out.data()), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(dacpo_ctx_last_error(ctx.get())).find("before the solve"),
            std::string::npos);
  EXPECT_EQ(dacpo_job_finish(job, nullptr), DACPO_ERR_INVALID_ARGUMENT);
  // in order from here on, the job completes
  for (size_t i = 1; i < nb; ++i)
    ASSERT_EQ(dacpo_job_orient_block(job, i, msg, sizeof(msg)), DACPO_OK) << msg;
  for (size_t e = 0; e < ne; ++e)
    ASSERT_EQ(dacpo_job_weigh_edge(job, e, msg, sizeof(msg)), DACPO_OK) << msg;
  ASSERT_EQ(dacpo_job_solve(job), DACPO_OK) << dacpo_ctx_last_error(ctx.get());
  EXPECT_EQ(dacpo_job_solve(job), DACPO_ERR_INVALID_ARGUMENT);
  ASSERT_EQ(dacpo_job_finish(job, out.data()), DACPO_OK)
      << dacpo_ctx_last_error(ctx.get());
  EXPECT_EQ(dacpo_job_finish(job, out.data()), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_job_num_blocks(nullptr), 0u);
  EXPECT_EQ(dacpo_job_solve(nullptr), DACPO_ERR_INVALID_ARGUMENT);
  dacpo_job_free(nullptr);
}
