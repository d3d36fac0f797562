// SPDX-License-Identifier: BSD-3-Clause
// Known answers for thin two-sided structures: two 1 m sheets at 2 cm spacing
// facing away from each other at gaps of 1.0, 1.5 and 2.0 spacings, clean and
// with noise sigma = 0.3 spacing, oriented from unsigned PCA normals through
// the public C API. The bounds are the errors this version reaches (measured,
// worst of seeds 1-3) with a small margin.
//
// Measured worst of seeds 1-3, % wrong:
//   gap (spacings)      1.0     1.5     2.0
//   c = 1.5 clean     50.00    0.23    0.13
//   c = 1.5 noisy     50.00   25.12    0.62
//   c = 4   clean      0.83    0.23    0.13
//   c = 4   noisy      2.73    1.56    0.62
//   c = 8   noisy      2.83   17.17   41.08
// With the default c = 1.5 (chosen for noisy depth frames) a gap of one
// spacing reads as one noisy sheet and both faces get one sign; c = 4 resolves
// every case here but costs the noisy real frames. The cases below pin what
// works; the default's failures are listed above, not asserted as passes.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

extern "C" {
#include "dacpo/dacpo.h"
#include "dacpo_scene.h"
}

namespace {

struct Case {
  double gap;   // in spacings
  double noise; // sigma in spacings
  double c;     // dipole c (0: the default)
  double bound; // % wrong, worst of seeds 1-3
};

double
orientSheets(const Case& c, uint64_t seed)
{
  const double h = 0.02;
  dacpo_scene sc{};
  char err[256];
  EXPECT_EQ(dacpo_scene_parallel_sheets(
                1.0, h, c.gap * h, c.noise * h, seed, &sc, err, sizeof(err)),
            0)
      << err;
  std::vector<float> nrm(3 * sc.n, 0.0f);
  dacpo_ctx* ctx = nullptr;
  EXPECT_EQ(dacpo_ctx_create(&ctx), DACPO_OK);
  dacpo_params p;
  dacpo_params_init(&p);
  p.estimate_normals = 1;
  p.seed = seed;
  if (c.c > 0.0)
    p.dipole_c = c.c;
  const dacpo_status s =
      dacpo_orient(ctx, &p, nullptr, nullptr, sc.xyz, nrm.data(), sc.n);
  EXPECT_EQ(s, DACPO_OK) << dacpo_ctx_last_error(ctx);
  const double wrong =
      s == DACPO_OK
          ? dacpo_score_oriented(sc.normals, nrm.data(), sc.n, nullptr, nullptr)
          : 100.0;
  dacpo_ctx_free(ctx);
  dacpo_scene_free(&sc);
  return wrong;
}

} // namespace

TEST(DacpoThinStructures, ParallelSheetsFacingAway)
{
  const std::vector<Case> cases = {
      {1.5, 0.0, 0.0, 0.5},
      {2.0, 0.0, 0.0, 0.5},
      {2.0, 0.3, 0.0, 1.5}, // default c
      {1.0, 0.0, 4.0, 1.5},
      {1.0, 0.3, 4.0, 4.0},
      {1.5, 0.3, 4.0, 3.0}, // c = 4
  };
  for (const Case& c : cases) {
    double worst = 0.0;
    for (uint64_t seed = 1; seed <= 3; ++seed)
      worst = std::max(worst, orientSheets(c, seed));
    RecordProperty("worst_percent", std::to_string(worst));
    EXPECT_LE(worst, c.bound) << "gap " << c.gap << " noise " << c.noise << " c "
                              << c.c;
  }
}
