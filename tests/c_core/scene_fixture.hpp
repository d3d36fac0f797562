// SPDX-License-Identifier: BSD-3-Clause
// A generated scene (wrappers/support/dacpo_scene.h) that frees itself: the
// fixture the stage tests share. `ok` says whether generation succeeded.
// orientEstimated: the pipeline's defaults on a scene's points.
#pragma once

#include <dacpo/dacpo.h>

#include <gtest/gtest.h>

#include "dacpo_scene.h"

#include <cstddef>
#include <cstdint>
#include <vector>

struct GeneratedScene {
  dacpo_scene s{};
  bool ok = false;
  GeneratedScene(unsigned kind, size_t points, uint64_t seed)
    : GeneratedScene(params(kind, points, seed))
  {
  }
  explicit GeneratedScene(const dacpo_scene_params& sp)
  {
    char err[256] = "";
    ok = dacpo_scene_generate(&sp, &s, err, sizeof(err)) == 0;
  }
  static dacpo_scene_params
  params(unsigned kind, size_t points, uint64_t seed)
  {
    dacpo_scene_params sp;
    dacpo_scene_params_init(&sp);
    sp.kind = kind;
    sp.target_points = points;
    sp.seed = seed;
    return sp;
  }
  GeneratedScene(const GeneratedScene&) = delete;
  GeneratedScene&
  operator=(const GeneratedScene&) = delete;
  ~GeneratedScene() { dacpo_scene_free(&s); }
};

// Orients n points with estimated normals, defaults otherwise, run seed 1:
// the normals in *nrm, the run's stats returned.
inline dacpo_stats
orientEstimated(const float* xyz, size_t n, std::vector<float>* nrm)
{
  nrm->assign(3 * n, 0.0f);
  dacpo_params p;
  dacpo_params_init(&p);
  p.estimate_normals = 1;
  p.seed = 1;
  dacpo_ctx* ctx = nullptr;
  EXPECT_EQ(dacpo_ctx_create(&ctx), DACPO_OK);
  EXPECT_EQ(dacpo_orient(ctx, &p, nullptr, nullptr, xyz, nrm->data(), n), DACPO_OK)
      << dacpo_ctx_last_error(ctx);
  const dacpo_stats st = *dacpo_ctx_stats(ctx);
  dacpo_ctx_free(ctx);
  return st;
}
