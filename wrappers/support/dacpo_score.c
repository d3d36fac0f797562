/* SPDX-License-Identifier: BSD-3-Clause */
/* The paper's metric (§6): the share of points whose normal makes more than 90
 * degrees with the ground truth, after one free sign for the whole cloud or
 * per label; and deterministic sign scrambling for tests. */
#include "dacpo_score.h"

#include "dacpo_rng.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The random stream of the scrambling (as dacpo_scene.c numbers its own). */
enum { STREAM_SCRAMBLE = 4 };

size_t
dacpo_scramble_signs(const float* normals_in,
                     float* normals_out,
                     size_t n,
                     uint64_t seed,
                     double fraction)
{
  dacpo_rng r;
  size_t k, flipped = 0;
  if (!normals_in || !normals_out || n == 0)
    return 0;
  if (!(fraction > 0.0)) /* also catches NaN */
    fraction = 0.0;
  if (fraction > 1.0)
    fraction = 1.0;
  k = (size_t)floor(fraction * (double)n + 0.5);
  if (k > n)
    k = n;
  dacpo_rng_seed(&r, seed, STREAM_SCRAMBLE);
  for (size_t i = 0; i < n; ++i) {
    /* Selection sampling: exactly k flips, uniformly placed. */
    const int flip = (double)(n - i) * dacpo_rng_uniform(&r) < (double)(k - flipped);
    const float sgn = flip ? -1.0f : 1.0f;
    flipped += (size_t)flip;
    for (int c = 0; c < 3; ++c)
      normals_out[3 * i + c] = sgn * normals_in[3 * i + c];
  }
  return flipped;
}

/* Per-point verdict: 0 agrees, 1 disagrees, 2 undecided (zero or non-finite dot,
 * wrong under either sign). */
static unsigned
score_state(const float* gt, const float* pred, size_t i)
{
  const double d = (double)gt[3 * i] * pred[3 * i] +
                   (double)gt[3 * i + 1] * pred[3 * i + 1] +
                   (double)gt[3 * i + 2] * pred[3 * i + 2];
  if (d > 0.0)
    return 0;
  if (d < 0.0)
    return 1;
  return 2;
}

static int
u64_cmp(const void* a, const void* b)
{
  const uint64_t x = *(const uint64_t*)a, y = *(const uint64_t*)b;
  return x < y ? -1 : (x > y ? 1 : 0);
}

double
dacpo_score_oriented(const float* gt,
                     const float* pred,
                     size_t n,
                     const int32_t* component,
                     size_t* wrong_out)
{
  size_t wrong = 0;
  if (wrong_out)
    *wrong_out = 0;
  if (n == 0)
    return 0.0;
  if (!gt || !pred)
    return -1.0;

  if (!component) {
    size_t cnt[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i)
      cnt[score_state(gt, pred, i)]++;
    wrong = (cnt[0] < cnt[1] ? cnt[0] : cnt[1]) + cnt[2];
  }
  else {
    int32_t lo = component[0], hi = component[0];
    size_t range;
    for (size_t i = 1; i < n; ++i) {
      if (component[i] < lo)
        lo = component[i];
      if (component[i] > hi)
        hi = component[i];
    }
    range = (size_t)((int64_t)hi - (int64_t)lo) + 1;
    if (range <= n + 1024) {
      /* Dense labels: three counters per label. */
      size_t* cnt = (size_t*)calloc(3 * range, sizeof(size_t));
      if (!cnt)
        return -1.0;
      for (size_t i = 0; i < n; ++i)
        cnt[3 * (size_t)((int64_t)component[i] - lo) + score_state(gt, pred, i)]++;
      for (size_t c = 0; c < range; ++c) {
        const size_t a = cnt[3 * c], d = cnt[3 * c + 1];
        wrong += (a < d ? a : d) + cnt[3 * c + 2];
      }
      free(cnt);
    }
    else {
      /* Sparse labels: sort (label, verdict) keys and sweep the runs. */
      uint64_t* key = (uint64_t*)malloc(n * sizeof(uint64_t));
      size_t i = 0;
      if (!key)
        return -1.0;
      for (size_t j = 0; j < n; ++j)
        key[j] =
            ((uint64_t)((int64_t)component[j] - lo) << 2) | score_state(gt, pred, j);
      qsort(key, n, sizeof(uint64_t), u64_cmp);
      while (i < n) {
        size_t cnt[3] = {0, 0, 0};
        const uint64_t label = key[i] >> 2;
        for (; i < n && (key[i] >> 2) == label; ++i)
          cnt[key[i] & 3u]++;
        wrong += (cnt[0] < cnt[1] ? cnt[0] : cnt[1]) + cnt[2];
      }
      free(key);
    }
  }
  if (wrong_out)
    *wrong_out = wrong;
  return 100.0 * (double)wrong / (double)n;
}
