// SPDX-License-Identifier: BSD-3-Clause
// One-shot marching cubes for the stage tests: an extractor made, used once and
// freed, its mesh copied into arrays the caller frees with dacpo_mesh_free.
#pragma once

#include "dacpo_mcubes.h"

#include <cstdlib>
#include <cstring>

inline dacpo_status
mcubes_once(const dacpo_grid* grid,
            const float* values,
            const uint8_t* domain,
            double iso,
            dacpo_mesh* out,
            dacpo_err* err)
{
  std::memset(out, 0, sizeof(*out));
  dacpo_mcubes* mc = nullptr;
  dacpo_status st = dacpo_mcubes_create(&mc, err);
  if (st != DACPO_OK)
    return st;
  const dacpo_mesh* m = nullptr;
  st = dacpo_mcubes_extract(mc, grid, values, domain, iso, &m, err);
  if (st == DACPO_OK && m->num_vertices > 0) {
    const size_t vb = 3 * m->num_vertices * sizeof(double);
    const size_t tb = 3 * m->num_triangles * sizeof(int32_t);
    out->vertices = static_cast<double*>(std::malloc(vb));
    out->triangles = static_cast<int32_t*>(std::malloc(tb > 0 ? tb : 1));
    if (out->vertices == nullptr || out->triangles == nullptr) {
      dacpo_mesh_free(out);
      st = DACPO_ERR_OUT_OF_MEMORY;
    }
    else {
      std::memcpy(out->vertices, m->vertices, vb);
      std::memcpy(out->triangles, m->triangles, tb);
      out->num_vertices = m->num_vertices;
      out->num_triangles = m->num_triangles;
    }
  }
  dacpo_mcubes_free(mc);
  return st;
}
