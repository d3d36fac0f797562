/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Synthetic scenes with ground-truth normals (see dacpo_scene.h).
 *
 * What it models: the evaluation inputs of the DACPO paper (section 6): open,
 * non-watertight indoor scans (ScanNet/SceneNN-like rooms with thin furniture),
 * their noisy variants (Gaussian displacement along a random direction, sigma
 * 0.004 / 0.008) and their randomly downsampled variants (100K / 10K points),
 * plus small analytic scenes for unit tests. (The paper's score is in
 * dacpo_score.c.)
 *
 * How: a scene is a list of analytic patches (rectangle with rectangular holes,
 * cylinder patch, annulus, sphere). Each patch gets a share of the points by the
 * largest-remainder rule on its area, so the total is exact and the density is
 * uniform; inside a patch the points are uniform by area (rejection for holes).
 * Geometry, downsampling and noise draw from separate xoshiro256** streams
 * derived from the seed, so the same seed gives the same surface points with or
 * without noise. The patches and the scene definitions are in
 * dacpo_scene_shapes.c; this file samples them.
 *
 * Cost: O(n) time, 28 bytes per point (xyz, normals, part id).
 * Failure modes: invalid parameters (-1), out of memory (-2); never crashes,
 * prints or aborts.
 */
#include "dacpo_scene.h"

#include "dacpo_rng.h"
#include "dacpo_scene_internal.h"
#include "dacpo_support_err.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SCENE_MAX_POINTS ((size_t)1000000000)

enum { SCENE_ERR_INVALID = -1, SCENE_ERR_NOMEM = -2 };

/* Random streams: one per purpose so that, e.g., adding noise does not move the
 * underlying surface samples. */
enum {
  STREAM_GEOMETRY = 1,
  STREAM_DOWNSAMPLE = 2,
  STREAM_NOISE = 3,
  STREAM_SCRAMBLE = 4, /* dacpo_score.c */
  STREAM_FUSED = 5
};

/* ------------------------------------------------------------------------- */
/* RNG: the core's xoshiro256** (dacpo_rng.h), plus two distributions.        */

/* Standard normal, Marsaglia's polar method (second value discarded to keep the
 * generator stateless beyond the xoshiro state). */
static double
rng_gauss(dacpo_rng* r)
{
  double u, v, s;
  do {
    u = 2.0 * dacpo_rng_uniform(r) - 1.0;
    v = 2.0 * dacpo_rng_uniform(r) - 1.0;
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  return u * sqrt(-2.0 * log(s) / s);
}

/* Uniform unit vector: z uniform in [-1, 1] and uniform azimuth (Archimedes). */
void
dacpo_scene_rng_unit_vector(dacpo_rng* r, double d[3])
{
  const double z = 2.0 * dacpo_rng_uniform(r) - 1.0;
  const double phi = 2.0 * SCENE_PI * dacpo_rng_uniform(r);
  const double rho = sqrt(fmax(0.0, 1.0 - z * z));
  d[0] = rho * cos(phi);
  d[1] = rho * sin(phi);
  d[2] = z;
}

/* Rodrigues: rot = I + sin(th) K + (1 - cos(th)) K^2, K the cross matrix of a. */
void
dacpo_scene_rotation(const double a[3], double th, double rot[9])
{
  const double K[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double k2 = 0.0;
      for (int m = 0; m < 3; ++m)
        k2 += K[3 * i + m] * K[3 * m + j];
      rot[3 * i + j] = (i == j) + sin(th) * K[3 * i + j] + (1.0 - cos(th)) * k2;
    }
}

/* ------------------------------------------------------------------------- */
/* Public functions.                                                          */

const char*
dacpo_scene_kind_name(unsigned kind)
{
  return kind < DACPO_SCENE_KIND_COUNT ? dacpo_scene_table[kind].name : NULL;
}

int
dacpo_scene_kind_from_name(const char* name, unsigned* kind)
{
  if (!name || !kind)
    return -1;
  for (unsigned i = 0; i < DACPO_SCENE_KIND_COUNT; ++i) {
    if (strcmp(name, dacpo_scene_table[i].name) == 0) {
      *kind = i;
      return 0;
    }
  }
  return -1;
}

void
dacpo_scene_params_init(dacpo_scene_params* params)
{
  if (!params)
    return;
  memset(params, 0, sizeof(*params));
  params->kind = DACPO_SCENE_ROOM;
  params->target_points = 100000;
  params->noise_sigma = 0.0;
  params->downsample_to = 0;
  params->seed = 1;
  params->fused_views = 0;
  params->fused_shift = 0.01;
  params->fused_angle = 0.2;
  params->views = 0;
  params->view_shift = 0.01;
  params->view_angle = 0.2;
}

void
dacpo_scene_free(dacpo_scene* scene)
{
  if (!scene)
    return;
  free(scene->xyz);
  free(scene->normals);
  free(scene->part);
  free(scene->part_object);
  free((void*)scene->object_name);
  memset(scene, 0, sizeof(*scene));
}

typedef struct quota_item {
  double frac;
  size_t index;
} quota_item;

/* Larger fractional part first; ties by index so the order is deterministic. */
static int
quota_cmp(const void* a, const void* b)
{
  const quota_item* x = (const quota_item*)a;
  const quota_item* y = (const quota_item*)b;
  if (x->frac != y->frac)
    return x->frac > y->frac ? -1 : 1;
  return x->index < y->index ? -1 : (x->index > y->index ? 1 : 0);
}

/* Largest-remainder apportionment of n points by area: exact total, each patch
 * within one point of its area share. */
static void
apportion(const double* area, size_t count, size_t n, size_t* out, quota_item* items)
{
  double total = 0.0;
  size_t assigned = 0;
  for (size_t i = 0; i < count; ++i)
    total += area[i];
  for (size_t i = 0; i < count; ++i) {
    const double q = (double)n * area[i] / total;
    double fl = floor(q);
    if (fl > (double)(n - assigned))
      fl = (double)(n - assigned);
    out[i] = (size_t)fl;
    assigned += out[i];
    items[i].frac = q - fl;
    items[i].index = i;
  }
  qsort(items, count, sizeof(*items), quota_cmp);
  for (size_t i = 0; assigned < n; i = (i + 1) % count) {
    out[items[i].index]++;
    assigned++;
  }
}

/* Keep exactly k of the n points, uniformly, in their original order (Knuth's
 * selection sampling, algorithm S). With views (info->views > 0), the views'
 * first points follow. */
static void
downsample(dacpo_scene* s, size_t k, uint64_t seed, dacpo_scene_view_info* info)
{
  dacpo_rng r;
  size_t kept = 0;
  unsigned view = 0;
  dacpo_rng_seed(&r, seed, STREAM_DOWNSAMPLE);
  for (size_t i = 0; i < s->n && kept < k; ++i) {
    for (; view < info->views && info->view_start[view] <= i; ++view)
      info->view_start[view] = kept;
    if ((double)(s->n - i) * dacpo_rng_uniform(&r) < (double)(k - kept)) {
      memmove(s->xyz + 3 * kept, s->xyz + 3 * i, 3 * sizeof(float));
      memmove(s->normals + 3 * kept, s->normals + 3 * i, 3 * sizeof(float));
      s->part[kept] = s->part[i];
      kept++;
    }
  }
  s->n = kept;
  for (; view <= info->views && info->views > 0; ++view)
    info->view_start[view] = kept;
  /* Shrinking; on a failed realloc the larger block stays valid. */
  {
    float* p = (float*)realloc(s->xyz, 3 * kept * sizeof(float));
    if (p)
      s->xyz = p;
    p = (float*)realloc(s->normals, 3 * kept * sizeof(float));
    if (p)
      s->normals = p;
  }
  {
    int32_t* q = (int32_t*)realloc(s->part, kept * sizeof(int32_t));
    if (q)
      s->part = q;
  }
}

/* Paper section 6: displacement sigma * N(0, 1) along a uniformly random
 * direction (mean length 0.8 sigma); normals keep the ground truth. */
static void
add_noise(dacpo_scene* s, double sigma, uint64_t seed)
{
  dacpo_rng r;
  dacpo_rng_seed(&r, seed, STREAM_NOISE);
  for (size_t i = 0; i < s->n; ++i) {
    double d[3];
    const double g = sigma * rng_gauss(&r);
    dacpo_scene_rng_unit_vector(&r, d);
    for (int k = 0; k < 3; ++k)
      s->xyz[3 * i + k] = (float)((double)s->xyz[3 * i + k] + g * d[k]);
  }
}

/* Views fused with a registration error: point i belongs to a random one of
 * `views`; view v > 0 is turned by `angle_deg` about a random axis through the
 * scene's centre and moved by `shift` in a random direction (its normals turn
 * with it, so the ground truth stays that of the surface each copy shows). */
static void
fuse_views(dacpo_scene* s, unsigned views, double shift, double angle_deg, uint64_t seed)
{
  dacpo_rng r;
  dacpo_rng_seed(&r, seed, STREAM_FUSED);
  double c[3] = {0.0, 0.0, 0.0};
  for (size_t i = 0; i < s->n; ++i)
    for (int k = 0; k < 3; ++k)
      c[k] += (double)s->xyz[3 * i + k] / (double)s->n;
  double rot[DACPO_SCENE_MAX_FUSED_VIEWS][9], move[DACPO_SCENE_MAX_FUSED_VIEWS][3];
  for (unsigned v = 0; v < views; ++v) {
    double a[3], t[3];
    dacpo_scene_rng_unit_vector(&r, a);
    dacpo_scene_rng_unit_vector(&r, t);
    dacpo_scene_rotation(a, v == 0 ? 0.0 : angle_deg * (3.14159265358979323846 / 180.0), rot[v]);
    for (int k = 0; k < 3; ++k)
      move[v][k] = v == 0 ? 0.0 : shift * t[k];
  }
  for (size_t i = 0; i < s->n; ++i) {
    const size_t v = dacpo_rng_below(&r, views);
    float* p = s->xyz + 3 * i;
    float* q = s->normals + 3 * i;
    const double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    const double m[3] = {q[0], q[1], q[2]};
    for (int k = 0; k < 3; ++k) {
      const double* R = rot[v] + 3 * k;
      p[k] = (float)(c[k] + R[0] * d[0] + R[1] * d[1] + R[2] * d[2] + move[v][k]);
      q[k] = (float)(R[0] * m[0] + R[1] * m[1] + R[2] * m[2]);
    }
  }
}

/* The parameters dacpo_scene_generate accepts (0, or SCENE_ERR_INVALID with
 * a message). */
static int
check_scene_params(const dacpo_scene_params* params, char* err, size_t errlen)
{
  const size_t n = params->target_points;
  if (params->kind >= DACPO_SCENE_KIND_COUNT) {
    dacpo_support_err(err,
                      errlen,
                      "unknown scene kind %u (valid: 0..%d)",
                      params->kind,
                      DACPO_SCENE_KIND_COUNT - 1);
    return SCENE_ERR_INVALID;
  }
  if (n == 0 || n > SCENE_MAX_POINTS || n > SIZE_MAX / (3 * sizeof(float))) {
    dacpo_support_err(
        err, errlen, "target_points %zu out of range (1..%zu)", n, SCENE_MAX_POINTS);
    return SCENE_ERR_INVALID;
  }
  if (!(params->noise_sigma >= 0.0) || !isfinite(params->noise_sigma)) {
    dacpo_support_err(
        err, errlen, "noise_sigma %g must be finite and >= 0", params->noise_sigma);
    return SCENE_ERR_INVALID;
  }
  if (params->fused_views > DACPO_SCENE_MAX_FUSED_VIEWS ||
      !(params->fused_shift >= 0.0) || !isfinite(params->fused_shift) ||
      !(params->fused_angle >= 0.0) || !isfinite(params->fused_angle)) {
    dacpo_support_err(err,
                      errlen,
                      "fused views %u (at most %d), shift %g and angle %g must be finite and >= 0",
                      params->fused_views,
                      DACPO_SCENE_MAX_FUSED_VIEWS,
                      params->fused_shift,
                      params->fused_angle);
    return SCENE_ERR_INVALID;
  }
  if (params->views > DACPO_SCENE_MAX_VIEWS ||
      (params->views > 0 && params->fused_views > 1) || !(params->view_shift >= 0.0) ||
      !isfinite(params->view_shift) || !(params->view_angle >= 0.0) ||
      !isfinite(params->view_angle)) {
    dacpo_support_err(err,
                      errlen,
                      "views %u (at most %d, not with fused views), shift %g and angle "
                      "%g must be finite and >= 0",
                      params->views,
                      DACPO_SCENE_MAX_VIEWS,
                      params->view_shift,
                      params->view_angle);
    return SCENE_ERR_INVALID;
  }
  if (params->downsample_to > n) {
    dacpo_support_err(err,
                      errlen,
                      "downsample_to %zu exceeds target_points %zu",
                      params->downsample_to,
                      n);
    return SCENE_ERR_INVALID;
  }
  return 0;
}

/* counts[i] points on patch i, in patch order, from the geometry stream (none
 * when counts is NULL); then the part -> object table and the object names. */
static void
sample_patches(const scene_builder* b,
               const size_t* counts,
               uint64_t seed,
               dacpo_scene* s)
{
  dacpo_rng r;
  size_t next = 0;
  dacpo_rng_seed(&r, seed, STREAM_GEOMETRY);
  for (size_t i = 0; i < b->count && counts; ++i) {
    for (size_t j = 0; j < counts[i]; ++j, ++next) {
      double pos[3] = {0.0, 0.0, 0.0}, nrm[3] = {0.0, 0.0, 1.0}, len;
      dacpo_scene_prim_sample(&b->prims[i], &r, pos, nrm);
      len = dacpo_scene_norm3(nrm);
      for (int k = 0; k < 3; ++k) {
        s->xyz[3 * next + k] = (float)pos[k];
        s->normals[3 * next + k] = (float)(nrm[k] / len);
      }
      s->part[next] = (int32_t)i;
    }
  }
  s->n = next;
  s->num_parts = b->count;
  s->num_objects = b->num_objects;
  for (size_t i = 0; i < b->count; ++i)
    s->part_object[i] = b->prims[i].object;
  for (size_t i = 0; i < b->num_objects; ++i)
    s->object_name[i] = b->names[i];
}

/* The points of the scene into s (allocated for target_points): uniform by
 * area or seen by the cameras, then downsampled, fused and noisy as asked. The
 * scratch arrays have one slot per patch. Returns 0, or -1 with a message. */
static int
fill_points(const scene_builder* b,
            const dacpo_scene_params* params,
            dacpo_scene* s,
            dacpo_scene_view_info* info,
            double* area,
            size_t* counts,
            quota_item* items,
            char* err,
            size_t errlen)
{
  if (params->views > 0) {
    sample_patches(b, NULL, params->seed, s); /* the part and object tables */
    if (dacpo_scene_sample_views(b, params, s, info, err, errlen) != 0)
      return SCENE_ERR_INVALID;
  }
  else {
    for (size_t i = 0; i < b->count; ++i)
      area[i] = dacpo_scene_prim_area(&b->prims[i]);
    apportion(area, b->count, params->target_points, counts, items);
    sample_patches(b, counts, params->seed, s);
  }
  if (params->downsample_to > 0 && params->downsample_to < s->n)
    downsample(s, params->downsample_to, params->seed, info);
  if (params->fused_views > 1)
    fuse_views(s, params->fused_views, params->fused_shift, params->fused_angle, params->seed);
  if (params->noise_sigma > 0.0)
    add_noise(s, params->noise_sigma, params->seed);
  return 0;
}

int
dacpo_scene_generate(const dacpo_scene_params* params,
                     dacpo_scene* out,
                     char* err,
                     size_t errlen)
{
  return dacpo_scene_generate_views(params, out, NULL, err, errlen);
}

int
dacpo_scene_generate_views(const dacpo_scene_params* params,
                           dacpo_scene* out,
                           dacpo_scene_view_info* info,
                           char* err,
                           size_t errlen)
{
  dacpo_scene_view_info spare;
  scene_builder b;
  double* area = NULL;
  size_t* counts = NULL;
  quota_item* items = NULL;
  dacpo_scene s;
  size_t n;
  int status = 0;

  if (err && errlen > 0)
    err[0] = '\0';
  if (out)
    memset(out, 0, sizeof(*out));
  if (!info)
    info = &spare;
  memset(info, 0, sizeof(*info));
  if (!params || !out) {
    dacpo_support_err(
        err, errlen, "dacpo_scene_generate: %s is NULL", !params ? "params" : "out");
    return SCENE_ERR_INVALID;
  }
  if ((status = check_scene_params(params, err, errlen)) != 0)
    return status;
  n = params->target_points;

  memset(&b, 0, sizeof(b));
  memset(&s, 0, sizeof(s));
  b.prims = (scene_prim*)malloc((SCENE_MAX_PRIMS + 1) * sizeof(scene_prim));
  if (!b.prims)
    goto oom;
  dacpo_scene_table[params->kind].build(&b);
  if (b.overflow || b.count == 0) {
    dacpo_support_err(err,
                      errlen,
                      "internal error: scene '%s' exceeds the builder's limits",
                      dacpo_scene_table[params->kind].name);
    status = SCENE_ERR_INVALID;
    goto done;
  }

  area = (double*)malloc(b.count * sizeof(double));
  counts = (size_t*)malloc(b.count * sizeof(size_t));
  items = (quota_item*)malloc(b.count * sizeof(quota_item));
  s.xyz = (float*)malloc(3 * n * sizeof(float));
  s.normals = (float*)malloc(3 * n * sizeof(float));
  s.part = (int32_t*)malloc(n * sizeof(int32_t));
  s.part_object = (int32_t*)malloc(b.count * sizeof(int32_t));
  s.object_name = (const char**)malloc(b.num_objects * sizeof(const char*));
  if (!area || !counts || !items || !s.xyz || !s.normals || !s.part || !s.part_object ||
      !s.object_name)
    goto oom;

  if ((status = fill_points(&b, params, &s, info, area, counts, items, err, errlen)) != 0)
    goto done;

  *out = s;
  memset(&s, 0, sizeof(s));
  goto done;

oom:
  dacpo_support_err(err, errlen, "out of memory generating %zu points", n);
  status = SCENE_ERR_NOMEM;
done:
  dacpo_scene_free(&s);
  free(area);
  free(counts);
  free(items);
  free(b.prims);
  return status;
}

size_t
dacpo_scene_scramble_signs(const dacpo_scene* scene,
                           float* normals_out,
                           uint64_t seed,
                           double fraction)
{
  if (!scene)
    return 0;
  return dacpo_scramble_signs(scene->normals, normals_out, scene->n, seed, fraction);
}

/* ------------------------------------------------------------------------- */
/* Two parallel sheets facing away from each other (thin-structure tests).    */

int
dacpo_scene_parallel_sheets(double size,
                            double spacing,
                            double gap,
                            double sigma,
                            uint64_t seed,
                            dacpo_scene* out,
                            char* err,
                            size_t errlen)
{
  if (!out || !(size > 0.0) || !(spacing > 0.0) || !(gap > 0.0) || !(sigma >= 0.0) ||
      size / spacing > 2000.0) {
    if (err && errlen)
      snprintf(err, errlen, "parallel sheets: bad argument");
    return -1;
  }
  memset(out, 0, sizeof(*out));
  const size_t m = (size_t)(size / spacing) + 1, n = 2 * m * m;
  out->xyz = malloc(3 * n * sizeof(float));
  out->normals = malloc(3 * n * sizeof(float));
  out->part = malloc(n * sizeof(int32_t));
  out->part_object = malloc(2 * sizeof(int32_t));
  out->object_name = malloc(sizeof(const char*));
  if (!out->xyz || !out->normals || !out->part || !out->part_object ||
      !out->object_name) {
    dacpo_scene_free(out);
    if (err && errlen)
      snprintf(err, errlen, "parallel sheets: out of memory");
    return -1;
  }
  dacpo_rng r;
  dacpo_rng_seed(&r, seed, 17);
  size_t k = 0;
  for (int sheet = 0; sheet < 2; ++sheet)
    for (size_t a = 0; a < m; ++a)
      for (size_t b = 0; b < m; ++b, ++k) {
        /* jittered grid, so the two sheets' points do not sit exactly above
         * each other; the lower sheet faces -z, the upper +z */
        double p[3] = {((double)a + 0.5 * (dacpo_rng_uniform(&r) - 0.5)) * spacing,
                       ((double)b + 0.5 * (dacpo_rng_uniform(&r) - 0.5)) * spacing,
                       sheet ? gap : 0.0};
        if (sigma > 0.0) {
          double d[3];
          const double g = sigma * rng_gauss(&r);
          dacpo_scene_rng_unit_vector(&r, d);
          for (int c = 0; c < 3; ++c)
            p[c] += g * d[c];
        }
        for (int c = 0; c < 3; ++c) {
          out->xyz[3 * k + c] = (float)p[c];
          out->normals[3 * k + c] = c == 2 ? (sheet ? 1.0f : -1.0f) : 0.0f;
        }
        out->part[k] = sheet;
      }
  out->n = n;
  out->num_parts = 2;
  out->part_object[0] = out->part_object[1] = 0;
  out->num_objects = 1;
  out->object_name[0] = "board";
  return 0;
}
