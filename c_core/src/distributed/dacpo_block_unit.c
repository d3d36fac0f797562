/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stages 2-3 of one block from its points alone (paper §4.2-4.3), and the
 * byte format of the work units that leave the process (dacpo_advanced.h).
 *
 * A block's unit reads only the block's own points and its overlap ring
 * (positions and PCA axes) and the run's parameters; it draws its random
 * numbers from the block's own stream of the seed. So the same bytes in give
 * the same bytes out wherever it runs: in dacpo_orient()'s threads, in
 * dacpo_job_orient_block(), or in another process from a task made by
 * dacpo_job_block_task() (the MPI tool). Both paths call
 * dacpo_block_unit_run(); only the transport differs.
 *
 * Byte format: a fixed header (magic, counts) and the arrays, native byte order
 * and struct layout: both ends must run the same build (one binary on a
 * cluster). Every count is checked against the size before an array is read,
 * and triangle indices against the vertex count, so a truncated or foreign
 * message is refused with INVALID_ARGUMENT, never read past its end.
 */
#include "dacpo_block_unit.h"

#include <dacpo/dacpo_advanced.h>

#include "dacpo_dipole.h"
#include "dacpo_vcr.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- stages 2-3 of one block -------------------------------------------- */

/* Stage 2's parameters for block b (its own random stream); thin: the block's
 * thin-part flags (output), cue: the side cue's agreement (output). */
static dacpo_dipole_params
unit_dipole_params(const dacpo_params* p, size_t b, uint8_t* thin, int8_t* cue)
{
  dacpo_dipole_params dp;
  dp.c = p->dipole_c;
  dp.orders = p->dipole_orders;
  dp.neighbors = p->dipole_neighbors;
  dp.graph_k = p->k;
  dp.final_sweep = p->dipole_final_sweep;
  dp.seed = p->seed;
  dp.stream = (uint64_t)b;
  dp.two_sheet = p->dipole_two_sheet;
  dp.layers = p->dipole_layers;
  dp.c_thin = p->dipole_c_thin;
  dp.restarts = p->dipole_restarts;
  dp.sides = p->dipole_sides;
  /* Many views: thin parts show both faces anywhere; 32 neighbours fit the
   * faces of narrow boards (shelves 6 samples deep) better than 24. */
  dp.sides_everywhere = p->scan_kind == DACPO_SCAN_MULTI_VIEW;
  dp.sides_fit_k = p->scan_kind == DACPO_SCAN_MULTI_VIEW ? 32 : 24;
  dp.thin_out = thin;
  dp.cue_out = cue;
  dp.restarts_out = NULL;
  return dp;
}

void
dacpo_block_out_free(dacpo_block_out* out)
{
  if (!out)
    return;
  free(out->nrm);
  free(out->conf);
  dacpo_mesh_free(&out->mesh);
  memset(out, 0, sizeof(*out));
}

/* Stage 3 on the stage-2 normals in out->nrm (the block keeps them when it is
 * too small for a Poisson solve). */
static dacpo_status
unit_ipsr(const dacpo_params* p,
          const double* xyz,
          size_t n,
          size_t n_own,
          const uint8_t* thin,
          int want_mesh,
          dacpo_block_out* out,
          dacpo_err* err)
{
  /* With iPSR off but VCR weights on, one Poisson solve still gives the block
   * its mesh (0 iterations: the normals are not changed). */
  if (!(p->ipsr_enabled || want_mesh) || n < DACPO_MIN_IPSR_POINTS)
    return DACPO_OK;
  dacpo_ipsr_params ip;
  dacpo_ipsr_params_default(&ip);
  ip.max_iterations = p->ipsr_enabled ? p->ipsr_max_iterations : 0;
  /* Stage 3 cannot see parts thinner than its grid: on a board 0.3-1
   * spacing thick its indicator function merges the two faces and turns one
   * over (two clean sheets half a spacing apart: 0 % wrong after stage 2,
   * 50 % after stage 3). Points where the stage-2 side cue fired keep their
   * stage-2 normal through the iterations. */
  ip.fixed = thin;
  const double t = dacpo_now();
  const dacpo_status st = dacpo_ipsr_block(
      xyz, out->nrm, n, n_own, &ip, want_mesh ? &out->mesh : NULL, &out->ipsr, err);
  out->seconds[1] = dacpo_now() - t;
  return st;
}

/* Stage 3 turns over points that stage 2 was sure of mostly where its grid
 * is too coarse for the part (room3002 clean, seed 1: of the 888 points whose
 * sign stage 3 changed, the 586 it got wrong had a median stage-2 confidence of
 * 0.46, the 302 it got right 0.25). Above this confidence (the share of restarts
 * that agree times the margin of the point's field, dacpo_dipole.c) the stage-2
 * sign is kept. Seeds 1 / 2, 8 rooms and 8 depth frames, mean % wrong:
 * rooms 6.58 -> 6.45 / 6.63 -> 6.66, frames 4.37 -> 4.18 / 3.98 -> 3.79;
 * 0.5: rooms 6.42, frames 4.43 (seed 1); 0.9: rooms 6.61. */
#define DACPO_IPSR_KEEP_CONFIDENT 0.7f

dacpo_status
dacpo_block_unit_run(const dacpo_params* p,
                     size_t block,
                     const double* xyz,
                     const double* axes,
                     size_t n,
                     size_t n_own,
                     int want_mesh,
                     dacpo_block_out* out,
                     dacpo_err* err)
{
  memset(out, 0, sizeof(*out));
  out->nrm = dacpo_malloc_array(3 * n, sizeof(double));
  out->conf = dacpo_malloc_array(n, sizeof(float));
  int8_t* sign = dacpo_malloc_array(n, sizeof(int8_t));
  uint8_t* thin = dacpo_malloc_array(n, sizeof(uint8_t));
  int8_t* cue = dacpo_malloc_array(n, sizeof(int8_t));
  dacpo_status st = DACPO_OK;
  if (!out->nrm || !out->conf || !sign || !thin || !cue) {
    st = DACPO_OOM(err);
    goto done;
  }
  dacpo_dipole_params dp = unit_dipole_params(p, block, thin, cue);
  size_t restarts = 0;
  dp.restarts_out = &restarts;
  const double t0 = dacpo_now();
  st = dacpo_dipole_orient_confidence(xyz, axes, n, &dp, sign, out->conf, err);
  out->seconds[0] = dacpo_now() - t0;
  out->restarts = (uint32_t)restarts;
  if (st != DACPO_OK)
    goto done;
  /* the cue's points keep their stage-2 sign through stage 3 (ip.fixed) */
  for (size_t i = 0; i < n_own; ++i)
    if (cue[i])
      out->cue_votes[cue[i] > 0 ? 0 : 1]++;
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      out->nrm[3 * i + d] = axes[3 * i + d] * (double)sign[i];
  st = unit_ipsr(p, xyz, n, n_own, thin, want_mesh, out, err);
  if (st != DACPO_OK)
    goto done;
  /* nrm started as sign * axis: a negative dot means stage 3 turned it over.
   * Where stage 2 was sure (confidence above DACPO_IPSR_KEEP_CONFIDENT), its
   * sign stays; elsewhere stage 3's stands, at half the confidence. */
  for (size_t i = 0; i < n_own; ++i) {
    const double* a = axes + 3 * i;
    double* m = out->nrm + 3 * i;
    const double d = (a[0] * m[0] + a[1] * m[1] + a[2] * m[2]) * (double)sign[i];
    if (d < 0.0 && out->conf[i] > DACPO_IPSR_KEEP_CONFIDENT)
      for (int k = 0; k < 3; ++k)
        m[k] = a[k] * (double)sign[i];
    else if (d < 0.0)
      out->conf[i] *= 0.5f;
  }
done:
  free(sign);
  free(thin);
  free(cue);
  if (st != DACPO_OK)
    dacpo_block_out_free(out);
  return st;
}

void
dacpo_block_unit_vcr_params(const dacpo_params* p, dacpo_vcr_params* vp)
{
  dacpo_vcr_params_default(vp);
  vp->image_size = p->vcr_image_size;
  vp->num_views = p->vcr_views;
}

/* ---- byte format --------------------------------------------------------- */

static const char task_magic[8] = {'D', 'A', 'C', 'P', 'O', 'B', 'T', '1'};
static const char result_magic[8] = {'D', 'A', 'C', 'P', 'O', 'B', 'R', '1'};
static const char edge_magic[8] = {'D', 'A', 'C', 'P', 'O', 'E', 'T', '1'};

/* Header fields are 64-bit: sizes mean the same on both ends. */
typedef struct unit_header {
  char magic[8];
  uint64_t id; /* block or edge */
  uint64_t n, n_own;
  uint64_t flag; /* task: want_mesh; result: has_mesh */
} unit_header;

typedef struct writer {
  uint8_t* p;
  size_t off;
} writer;

static void
put(writer* w, const void* src, size_t bytes)
{
  if (bytes)
    memcpy(w->p + w->off, src, bytes);
  w->off += bytes;
}

typedef struct reader {
  const uint8_t* p;
  size_t size, off;
} reader;

/* Copies `count` items of `item` bytes unless that runs past the end. */
static int
get(reader* r, void* dst, size_t count, size_t item)
{
  if (item != 0 && count > (r->size - r->off) / item)
    return 0;
  if (count != 0 && item != 0)
    memcpy(dst, r->p + r->off, count * item);
  r->off += count * item;
  return 1;
}

static size_t
mesh_bytes(const dacpo_mesh* m)
{
  return 2 * sizeof(uint64_t) + m->num_vertices * 3 * sizeof(double) +
         m->num_triangles * 3 * sizeof(int32_t);
}

static void
put_mesh(writer* w, const dacpo_mesh* m)
{
  const uint64_t c[2] = {m->num_vertices, m->num_triangles};
  put(w, c, sizeof(c));
  put(w, m->vertices, m->num_vertices * 3 * sizeof(double));
  put(w, m->triangles, m->num_triangles * 3 * sizeof(int32_t));
}

static dacpo_status
get_mesh(reader* r, dacpo_mesh* m, dacpo_err* err)
{
  uint64_t c[2];
  DACPO_CHECK(err,
              get(r, c, 2, sizeof(uint64_t)) && c[0] <= (r->size - r->off) / 24 &&
                  c[1] <= (r->size - r->off) / 12,
              DACPO_ERR_INVALID_ARGUMENT,
              "unit: a mesh runs past the end of the message");
  m->num_vertices = (size_t)c[0];
  m->num_triangles = (size_t)c[1];
  m->vertices = dacpo_malloc_array(3 * m->num_vertices + 1, sizeof(double));
  m->triangles = dacpo_malloc_array(3 * m->num_triangles + 1, sizeof(int32_t));
  if (!m->vertices || !m->triangles)
    return DACPO_OOM(err);
  DACPO_CHECK(err,
              get(r, m->vertices, 3 * m->num_vertices, sizeof(double)) &&
                  get(r, m->triangles, 3 * m->num_triangles, sizeof(int32_t)),
              DACPO_ERR_INVALID_ARGUMENT,
              "unit: a mesh runs past the end of the message");
  for (size_t v = 0; v < 3 * m->num_vertices; ++v)
    DACPO_CHECK(err,
                isfinite(m->vertices[v]),
                DACPO_ERR_INVALID_ARGUMENT,
                "unit: mesh vertex %zu is not finite",
                v / 3);
  for (size_t t = 0; t < 3 * m->num_triangles; ++t)
    DACPO_CHECK(err,
                m->triangles[t] >= 0 && (size_t)m->triangles[t] < m->num_vertices,
                DACPO_ERR_INVALID_ARGUMENT,
                "unit: triangle corner %zu names vertex %ld of %zu",
                t,
                (long)m->triangles[t],
                m->num_vertices);
  return DACPO_OK;
}

static dacpo_status
alloc_bytes(size_t size, void** bytes, writer* w, dacpo_err* err)
{
  *bytes = malloc(size);
  if (!*bytes)
    return DACPO_OOM(err);
  w->p = *bytes;
  w->off = 0;
  return DACPO_OK;
}

static dacpo_status
get_header(
    reader* r, const char magic[8], const char* what, unit_header* h, dacpo_err* err)
{
  DACPO_CHECK(err,
              r->p != NULL && get(r, h, 1, sizeof(*h)) &&
                  memcmp(h->magic, magic, sizeof(h->magic)) == 0,
              DACPO_ERR_INVALID_ARGUMENT,
              "unit: %zu bytes are no %s of this build",
              r->size,
              what);
  return DACPO_OK;
}

dacpo_status
dacpo_block_task_pack(const dacpo_params* p,
                      size_t block,
                      const double* xyz,
                      const double* axes,
                      size_t n,
                      size_t n_own,
                      int want_mesh,
                      void** bytes,
                      size_t* size,
                      dacpo_err* err)
{
  unit_header h = {{0}, block, n, n_own, (uint64_t)(want_mesh != 0)};
  memcpy(h.magic, task_magic, sizeof(h.magic));
  *size = sizeof(h) + sizeof(*p) + 6 * n * sizeof(double);
  if (!bytes)
    return DACPO_OK;
  writer w = {NULL, 0};
  DACPO_TRY(alloc_bytes(*size, bytes, &w, err));
  put(&w, &h, sizeof(h));
  put(&w, p, sizeof(*p));
  put(&w, xyz, 3 * n * sizeof(double));
  put(&w, axes, 3 * n * sizeof(double));
  return DACPO_OK;
}

dacpo_status
dacpo_block_result_pack(size_t block,
                        size_t n,
                        size_t n_own,
                        const dacpo_block_out* out,
                        int has_mesh,
                        void** bytes,
                        size_t* size,
                        dacpo_err* err)
{
  unit_header h = {{0}, block, n, n_own, (uint64_t)(has_mesh != 0)};
  memcpy(h.magic, result_magic, sizeof(h.magic));
  *size = sizeof(h) + sizeof(out->cue_votes) + sizeof(out->restarts) + sizeof(out->seconds) +
          sizeof(out->ipsr) + 3 * n * sizeof(double) + n_own * sizeof(float) +
          (has_mesh ? mesh_bytes(&out->mesh) : 0);
  writer w = {NULL, 0};
  DACPO_TRY(alloc_bytes(*size, bytes, &w, err));
  put(&w, &h, sizeof(h));
  put(&w, out->cue_votes, sizeof(out->cue_votes));
  put(&w, &out->restarts, sizeof(out->restarts));
  put(&w, out->seconds, sizeof(out->seconds));
  put(&w, &out->ipsr, sizeof(out->ipsr));
  put(&w, out->nrm, 3 * n * sizeof(double));
  put(&w, out->conf, n_own * sizeof(float));
  if (has_mesh)
    put_mesh(&w, &out->mesh);
  return DACPO_OK;
}

static dacpo_status
result_unpack(reader* r, unit_header* h, dacpo_block_out* out, dacpo_err* err)
{
  DACPO_TRY(get_header(r, result_magic, "block result", h, err));
  DACPO_CHECK(err,
              h->n_own <= h->n && h->n <= (r->size - r->off) / 24,
              DACPO_ERR_INVALID_ARGUMENT,
              "unit: block result of %llu points (%llu own) in %zu bytes",
              (unsigned long long)h->n,
              (unsigned long long)h->n_own,
              r->size);
  const size_t n = (size_t)h->n, no = (size_t)h->n_own;
  out->nrm = dacpo_malloc_array(3 * n + 1, sizeof(double));
  out->conf = dacpo_malloc_array(no + 1, sizeof(float));
  if (!out->nrm || !out->conf)
    return DACPO_OOM(err);
  DACPO_CHECK(err,
              get(r, out->cue_votes, 2, sizeof(uint32_t)) &&
                  get(r, &out->restarts, 1, sizeof(uint32_t)) &&
                  get(r, out->seconds, 2, sizeof(double)) &&
                  get(r, &out->ipsr, 1, sizeof(out->ipsr)) &&
                  get(r, out->nrm, 3 * n, sizeof(double)) &&
                  get(r, out->conf, no, sizeof(float)),
              DACPO_ERR_INVALID_ARGUMENT,
              "unit: block result runs past the end of the message");
  for (size_t i = 0; i < n; ++i)
    DACPO_CHECK(err,
                isfinite(out->nrm[3 * i]) && isfinite(out->nrm[3 * i + 1]) &&
                    isfinite(out->nrm[3 * i + 2]) &&
                    (i >= no || (out->conf[i] >= 0.0f && out->conf[i] <= 1.0f)),
                DACPO_ERR_INVALID_ARGUMENT,
                "unit: normal or confidence %zu of the block result is out of range",
                i);
  if (h->flag)
    DACPO_TRY(get_mesh(r, &out->mesh, err));
  DACPO_CHECK(err,
              r->off == r->size,
              DACPO_ERR_INVALID_ARGUMENT,
              "unit: %zu bytes after the block result",
              r->size - r->off);
  return DACPO_OK;
}

dacpo_status
dacpo_block_result_unpack(const void* bytes,
                          size_t size,
                          size_t* block,
                          size_t* n,
                          size_t* n_own,
                          int* has_mesh,
                          dacpo_block_out* out,
                          dacpo_err* err)
{
  memset(out, 0, sizeof(*out));
  reader r = {bytes, size, 0};
  unit_header h;
  const dacpo_status st = result_unpack(&r, &h, out, err);
  if (st != DACPO_OK) {
    dacpo_block_out_free(out);
    return st;
  }
  *block = (size_t)h.id;
  *n = (size_t)h.n;
  *n_own = (size_t)h.n_own;
  *has_mesh = h.flag != 0;
  return DACPO_OK;
}

dacpo_status
dacpo_edge_task_pack(const dacpo_params* p,
                     size_t edge,
                     const dacpo_mesh* a,
                     const dacpo_mesh* b,
                     void** bytes,
                     size_t* size,
                     dacpo_err* err)
{
  unit_header h = {{0}, edge, 0, 0, 0};
  memcpy(h.magic, edge_magic, sizeof(h.magic));
  *size = sizeof(h) + sizeof(*p) + mesh_bytes(a) + mesh_bytes(b);
  if (!bytes)
    return DACPO_OK;
  writer w = {NULL, 0};
  DACPO_TRY(alloc_bytes(*size, bytes, &w, err));
  put(&w, &h, sizeof(h));
  put(&w, p, sizeof(*p));
  put_mesh(&w, a);
  put_mesh(&w, b);
  return DACPO_OK;
}

/* ---- public: the units of another process (dacpo_advanced.h) ------------- */

dacpo_status
dacpo_unit_message(const dacpo_err* err, char* msg, size_t msg_size)
{
  if (msg && msg_size > 0)
    snprintf(msg, msg_size, "%s", err->code != DACPO_OK ? err->msg : "");
  return err->code;
}

/* The parameters a task carries, checked as dacpo_orient() checks them. */
static dacpo_status
get_params(reader* r, dacpo_params* p, dacpo_err* err)
{
  DACPO_CHECK(err,
              get(r, p, 1, sizeof(*p)),
              DACPO_ERR_INVALID_ARGUMENT,
              "unit: the parameters run past the end of the message");
  char msg[256];
  DACPO_CHECK(err,
              dacpo_params_validate(p, msg, sizeof(msg)) == DACPO_OK,
              DACPO_ERR_INVALID_ARGUMENT,
              "unit: %s",
              msg);
  return DACPO_OK;
}

/* A task skips the input checks of stage 0: its points must be finite and
 * its axes unit vectors, as the job made them. */
static dacpo_status
check_points(const double* xyz, const double* axes, size_t n, dacpo_err* err)
{
  for (size_t i = 0; i < n; ++i) {
    const double* p = xyz + 3 * i;
    const double* a = axes + 3 * i;
    const double len2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    DACPO_CHECK(err,
                isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]) &&
                    fabs(len2 - 1.0) < 1e-6,
                DACPO_ERR_INVALID_ARGUMENT,
                "unit: point %zu of the block task is not finite or its axis not a "
                "unit vector",
                i);
  }
  return DACPO_OK;
}

static dacpo_status
block_task_run(const void* task,
               size_t task_size,
               void** result,
               size_t* result_size,
               dacpo_err* err)
{
  reader r = {task, task_size, 0};
  unit_header h;
  dacpo_params p;
  DACPO_TRY(get_header(&r, task_magic, "block task", &h, err));
  DACPO_TRY(get_params(&r, &p, err));
  DACPO_CHECK(err,
              h.n >= 1 && h.n_own <= h.n && h.n <= (r.size - r.off) / 48 &&
                  r.size - r.off == h.n * 48,
              DACPO_ERR_INVALID_ARGUMENT,
              "unit: block task of %llu points (%llu own) in %zu bytes",
              (unsigned long long)h.n,
              (unsigned long long)h.n_own,
              task_size);
  const size_t n = (size_t)h.n;
  /* the arrays may sit at any offset of the caller's buffer: copy them */
  double* xyz = dacpo_malloc_array(3 * n, sizeof(double));
  double* axes = dacpo_malloc_array(3 * n, sizeof(double));
  dacpo_block_out out;
  memset(&out, 0, sizeof(out));
  dacpo_status st = xyz && axes ? DACPO_OK : DACPO_OOM(err);
  if (st == DACPO_OK) {
    get(&r, xyz, 3 * n, sizeof(double));
    get(&r, axes, 3 * n, sizeof(double));
    st = check_points(xyz, axes, n, err);
  }
  if (st == DACPO_OK) {
    st = dacpo_block_unit_run(
        &p, (size_t)h.id, xyz, axes, n, (size_t)h.n_own, h.flag != 0, &out, err);
  }
  if (st == DACPO_OK)
    st = dacpo_block_result_pack(
        (size_t)h.id, n, (size_t)h.n_own, &out, h.flag != 0, result, result_size, err);
  free(xyz);
  free(axes);
  dacpo_block_out_free(&out);
  return st;
}

dacpo_status
dacpo_block_task_run(const void* task,
                     size_t task_size,
                     void** result,
                     size_t* result_size,
                     char* msg,
                     size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  if (!result || !result_size)
    dacpo_err_set(&err, DACPO_ERR_INVALID_ARGUMENT, "unit: result is NULL");
  else {
    *result = NULL;
    *result_size = 0;
    block_task_run(task, task_size, result, result_size, &err);
  }
  return dacpo_unit_message(&err, msg, msg_size);
}

static dacpo_status
edge_task_run(const void* task,
              size_t task_size,
              double* alpha,
              double* alpha_bar,
              dacpo_err* err)
{
  reader r = {task, task_size, 0};
  unit_header h;
  dacpo_params p;
  dacpo_mesh a, b;
  memset(&a, 0, sizeof(a));
  memset(&b, 0, sizeof(b));
  DACPO_TRY(get_header(&r, edge_magic, "edge task", &h, err));
  DACPO_TRY(get_params(&r, &p, err));
  dacpo_status st = get_mesh(&r, &a, err);
  if (st == DACPO_OK)
    st = get_mesh(&r, &b, err);
  if (st == DACPO_OK && r.off != r.size)
    st = dacpo_err_set(err,
                       DACPO_ERR_INVALID_ARGUMENT,
                       "unit: %zu bytes after the edge task",
                       r.size - r.off);
  if (st == DACPO_OK) {
    dacpo_vcr_params vp;
    dacpo_block_unit_vcr_params(&p, &vp);
    st = dacpo_vcr_edge(&a, &b, &vp, alpha, alpha_bar, NULL, err);
  }
  dacpo_mesh_free(&a);
  dacpo_mesh_free(&b);
  return st;
}

dacpo_status
dacpo_edge_task_run(const void* task,
                    size_t task_size,
                    double* alpha,
                    double* alpha_bar,
                    char* msg,
                    size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  if (!alpha || !alpha_bar)
    dacpo_err_set(&err, DACPO_ERR_INVALID_ARGUMENT, "unit: alpha is NULL");
  else
    edge_task_run(task, task_size, alpha, alpha_bar, &err);
  return dacpo_unit_message(&err, msg, msg_size);
}

void
dacpo_unit_bytes_free(void* bytes)
{
  free(bytes);
}
