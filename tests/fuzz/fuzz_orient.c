/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * libFuzzer target: dacpo_orient() on small clouds built from the input bytes.
 *
 * Layout: byte 0-7 parameters (k, blocks, normal source, estimate, weights,
 * sign policy, disconnected policy, seed), then 12 bytes per point: three
 * int32 read as coordinates through a per-cloud scale chosen by byte 8 (from
 * 1e-30 to 1e30, so huge and tiny clouds), with special values mapped in: a
 * few int patterns become NaN / inf / duplicates of the previous point, and
 * collinear or coplanar clouds come out of repeated bytes. Normals (when
 * given) come from the same bytes rotated. At most 96 points: every run is a
 * whole pipeline.
 *
 * Contract checked: no crash, no sanitizer report, a status from the enum, a
 * message on failure, and on success finite unit normals for every finite
 * input point.
 */
#include <dacpo/dacpo.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define MAX_POINTS 96

static float
coord(const uint8_t* b, double scale, float prev)
{
  int32_t v;
  memcpy(&v, b, 4);
  switch (v & 0xff) {
  case 0xf0:
    return NAN;
  case 0xf1:
    return INFINITY;
  case 0xf2:
    return prev; /* duplicates and collinear runs */
  default:
    return (float)((double)(v >> 8) * scale);
  }
}

int
LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  if (size < 9)
    return 0;
  size_t n = (size - 9) / 12;
  if (n > MAX_POINTS)
    n = MAX_POINTS;
  static const double scales[] = {1e-30, 1e-12, 1e-3, 1.0 / 1024, 1.0, 1e3, 1e12, 1e30};
  const double scale = scales[data[8] % 8];
  float* xyz = malloc(3 * (n ? n : 1) * sizeof(float));
  float* nrm = malloc(3 * (n ? n : 1) * sizeof(float));
  if (!xyz || !nrm) {
    free(xyz);
    free(nrm);
    return 0;
  }
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      const uint8_t* b = data + 9 + 12 * i + 4 * d;
      xyz[3 * i + d] = coord(b, scale, i ? xyz[3 * (i - 1) + d] : 0.0f);
      nrm[3 * i + d] = (float)((int)b[(d + 1) % 4] - 128);
    }

  dacpo_params p;
  dacpo_params_init(&p);
  p.k = 2 + data[0] % 20;
  p.num_blocks = data[1] % 6;
  p.estimate_normals = data[3] & 1;
  p.normal_k = 3 + data[3] % 13;
  p.edge_weight = (dacpo_edge_weight)(data[4] % 3);
  p.ipsr_enabled = (data[4] >> 2) & 1;
  p.sign_policy = (dacpo_sign_policy)(data[5] % 3);
  p.viewpoint[0] = data[5];
  p.disconnected = (dacpo_disconnected_policy)(data[6] % 4);
  p.seed = data[7];
  p.num_threads = 1;
  p.dipole_restarts = 1 + data[2] % 3;
  p.vcr_image_size = 16 + data[2] % 32;
  p.solver_time_limit = 2.0;

  dacpo_ctx* ctx = NULL;
  if (dacpo_ctx_create(&ctx) != DACPO_OK) {
    free(xyz);
    free(nrm);
    return 0;
  }
  const dacpo_status s = dacpo_orient(ctx, &p, NULL, NULL, xyz, nrm, n);
  if (s != DACPO_OK) {
    const char* msg = dacpo_ctx_last_error(ctx);
    if (!msg || !msg[0] || !dacpo_status_string(s))
      abort(); /* every failure says why */
  }
  else {
    for (size_t i = 0; i < n; ++i) {
      if (!(isfinite(xyz[3 * i]) && isfinite(xyz[3 * i + 1]) &&
            isfinite(xyz[3 * i + 2])))
        continue;
      const double len = sqrt((double)nrm[3 * i] * nrm[3 * i] +
                              (double)nrm[3 * i + 1] * nrm[3 * i + 1] +
                              (double)nrm[3 * i + 2] * nrm[3 * i + 2]);
      if (!(fabs(len - 1.0) < 1e-3))
        abort(); /* success must mean a unit normal for every point */
    }
  }
  dacpo_ctx_free(ctx);
  free(xyz);
  free(nrm);
  return 0;
}
