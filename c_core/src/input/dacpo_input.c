/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0, input: validate the caller's arrays and
 * merge exact duplicates.
 *
 * The dipole field of paper Eq. 1 divides by |r|^3, so coincident points must not
 * both enter it; they are merged into one distinct point and every input point
 * keeps a link to its distinct point, so results go back to all of them.
 *
 * dacpo_input_check: O(n); reports the FIRST bad point by index.
 * dacpo_cloud_build: O(n) stable LSD radix sort of (x, y, z) keys (6 passes of 16
 *   bits over 16-byte records, so 32 bytes per point of scratch); distinct points
 *   are numbered in the order of their lowest input index, which is their
 *   representative. Deterministic and independent of threads.
 * Failure modes: NULL pointers / too many points (INVALID_ARGUMENT), count == 0
 *   (EMPTY_INPUT), NaN/inf or zero-length normals (NONFINITE_INPUT), allocation
 *   (OUT_OF_MEMORY). */
#include "dacpo_input.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Smallest accepted normal length: anything shorter carries no direction. */
#define DACPO_MIN_NORMAL_NORM 1e-20

static const char*
nonfinite_name(float v)
{
  if (isnan(v))
    return "nan";
  return v > 0 ? "inf" : "-inf";
}

dacpo_status
dacpo_input_check(const float* xyz, const float* normals, size_t count, dacpo_err* err)
{
  /* An empty std::vector may hand over data() == NULL: report it as empty. */
  DACPO_CHECK(err, count > 0, DACPO_ERR_EMPTY_INPUT, "the input has no points");
  DACPO_CHECK(err, xyz != NULL, DACPO_ERR_INVALID_ARGUMENT, "xyz is NULL");
  DACPO_CHECK(err,
              count <= (size_t)INT32_MAX - 1,
              DACPO_ERR_INVALID_ARGUMENT,
              "%zu points exceed the supported maximum of %d",
              count,
              INT32_MAX - 1);
  for (size_t i = 0; i < count; ++i) {
    for (int d = 0; d < 3; ++d) {
      float v = xyz[3 * i + d];
      if (!isfinite(v))
        return dacpo_err_set(err,
                             DACPO_ERR_NONFINITE_INPUT,
                             "point %zu has a non-finite coordinate (%s)",
                             i,
                             nonfinite_name(v));
    }
  }
  if (!normals)
    return DACPO_OK;
  for (size_t i = 0; i < count; ++i) {
    double n2 = 0.0;
    for (int d = 0; d < 3; ++d) {
      float v = normals[3 * i + d];
      if (!isfinite(v))
        return dacpo_err_set(err,
                             DACPO_ERR_NONFINITE_INPUT,
                             "point %zu has a non-finite normal (%s)",
                             i,
                             nonfinite_name(v));
      n2 += (double)v * (double)v;
    }
    if (!(n2 >= DACPO_MIN_NORMAL_NORM * DACPO_MIN_NORMAL_NORM))
      return dacpo_err_set(
          err, DACPO_ERR_NONFINITE_INPUT, "point %zu has a zero-length normal", i);
  }
  return DACPO_OK;
}

/* One sort record: order-preserving keys of x, y, z and the input index. */
typedef struct key_rec {
  uint32_t key[3];
  int32_t idx;
} key_rec;

/* Maps a finite float to an unsigned key with the same order; -0 and +0 get
 * the same key, so they merge. */
static uint32_t
float_key(float v)
{
  if (v == 0.0f)
    v = 0.0f;
  uint32_t b;
  memcpy(&b, &v, sizeof(b));
  return (b & 0x80000000u) ? ~b : (b | 0x80000000u);
}

/* Stable LSD radix sort by (key[0], key[1], key[2]); the records start in input
 * order, so equal points end up in increasing input order. Returns the buffer
 * holding the result (a or b). */
static key_rec*
radix_sort(key_rec* a, key_rec* b, size_t n, size_t* hist)
{
  key_rec* src = a;
  key_rec* dst = b;
  /* least significant digit first: z low, z high, y low, ..., x high */
  for (int pass = 0; pass < 6; ++pass) {
    int coord = 2 - pass / 2;
    int shift = (pass % 2) * 16;
    memset(hist, 0, 65536 * sizeof(size_t));
    for (size_t i = 0; i < n; ++i)
      ++hist[(src[i].key[coord] >> shift) & 0xFFFFu];
    /* a digit shared by every record does not reorder anything */
    if (hist[(src[0].key[coord] >> shift) & 0xFFFFu] == n)
      continue;
    size_t sum = 0;
    for (size_t v = 0; v < 65536; ++v) {
      size_t c = hist[v];
      hist[v] = sum;
      sum += c;
    }
    for (size_t i = 0; i < n; ++i)
      dst[hist[(src[i].key[coord] >> shift) & 0xFFFFu]++] = src[i];
    key_rec* t = src;
    src = dst;
    dst = t;
  }
  return src;
}

static int
same_key(const key_rec* a, const key_rec* b)
{
  return a->key[0] == b->key[0] && a->key[1] == b->key[1] && a->key[2] == b->key[2];
}

dacpo_status
dacpo_cloud_build(const float* xyz,
                  const float* normals,
                  size_t count,
                  dacpo_cloud* out,
                  dacpo_err* err)
{
  DACPO_CHECK(err, out != NULL, DACPO_ERR_INVALID_ARGUMENT, "cloud: out is NULL");
  memset(out, 0, sizeof(*out));
  /* The radix keys assume finite values. */
  DACPO_TRY(dacpo_input_check(xyz, normals, count, err));

  key_rec* a = dacpo_malloc_array(count, sizeof(key_rec));
  key_rec* b = dacpo_malloc_array(count, sizeof(key_rec));
  size_t* hist = dacpo_malloc_array(65536, sizeof(size_t));
  int32_t* map = dacpo_malloc_array(count, sizeof(int32_t));
  if (!a || !b || !hist || !map) {
    free(a);
    free(b);
    free(hist);
    free(map);
    return DACPO_OOM(err);
  }
  for (size_t i = 0; i < count; ++i) {
    for (int d = 0; d < 3; ++d)
      a[i].key[d] = float_key(xyz[3 * i + d]);
    a[i].idx = (int32_t)i;
  }
  const key_rec* s = radix_sort(a, b, count, hist);

  /* map[i] = representative (lowest input index) of i's group: the first
   * record of each run of equal keys, thanks to the stable sort. */
  for (size_t g = 0; g < count;) {
    size_t e = g + 1;
    while (e < count && same_key(&s[e], &s[g]))
      ++e;
    for (size_t j = g; j < e; ++j)
      map[s[j].idx] = s[g].idx;
    g = e;
  }
  free(a);
  free(b);
  free(hist);

  /* Number distinct points by their representative's input index; a
   * representative precedes every other member, so members look up its id. */
  size_t n = 0;
  for (size_t i = 0; i < count; ++i) {
    int32_t rep = map[i];
    map[i] = ((size_t)rep == i) ? (int32_t)n++ : map[rep];
  }

  out->n = n;
  out->input_count = count;
  out->input_to_point = map;
  out->xyz = dacpo_malloc_array(n, 3 * sizeof(double));
  out->nrm = dacpo_calloc_array(n, 3 * sizeof(double));
  out->rep_input = dacpo_malloc_array(n, sizeof(int32_t));
  if (!out->xyz || !out->nrm || !out->rep_input) {
    dacpo_cloud_free(out);
    return DACPO_OOM(err);
  }
  size_t next = 0;
  for (size_t i = 0; i < count; ++i) {
    if ((size_t)map[i] != next)
      continue; /* not the first member of a new group */
    out->rep_input[next] = (int32_t)i;
    for (int d = 0; d < 3; ++d)
      out->xyz[3 * next + d] = (double)xyz[3 * i + d];
    if (normals) {
      double v[3] = {normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]};
      double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      for (int d = 0; d < 3; ++d)
        out->nrm[3 * next + d] = v[d] / len;
    }
    ++next;
  }
  return DACPO_OK;
}

void
dacpo_cloud_free(dacpo_cloud* cloud)
{
  if (!cloud)
    return;
  free(cloud->xyz);
  free(cloud->nrm);
  free(cloud->rep_input);
  free(cloud->input_to_point);
  memset(cloud, 0, sizeof(*cloud));
}
