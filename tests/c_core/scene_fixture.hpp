// SPDX-License-Identifier: BSD-3-Clause
// A generated scene (wrappers/support/dacpo_scene.h) that frees itself: the
// fixture the stage tests share. `ok` says whether generation succeeded.
#pragma once

#include "dacpo_scene.h"

#include <cstddef>
#include <cstdint>

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
