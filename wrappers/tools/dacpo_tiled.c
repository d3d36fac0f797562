/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Out-of-core orientation (dacpo_tiled.h). Passes over the data:
 *
 *   1 sample  read the PLY in chunks, check every point is finite, keep every
 *             s-th one; dacpo_tile_plan_create() cuts space into tiles
 *   2 route   read it again; every point goes to its own tile's file and to
 *             the files of the tiles whose halo holds it (index + xyz)
 *   3 tiles   per tile: its file (in input order) -> dacpo_orient(); own
 *             points' normals go to the output at their input position, the
 *             halo points' normals to one side file
 *   4 join    each halo normal against its owner's (read back from the
 *             output) -> dacpo_tile_overlap evidence -> dacpo_tile_join()
 *   5 flip    negate the normals of the flipped tiles in place; rename the
 *             temporary output onto the output
 *
 * Peak memory: the sample (12 bytes x 200K), one chunk, one tile's
 * dacpo_orient() run, and the evidence per tile pair. Disk: 20 bytes per routed point,
 * 24 per halo point, the output. Errors leave no output and no temporary file.
 */
#define _FILE_OFFSET_BITS 64
#define _POSIX_C_SOURCE 200809L

#include "dacpo_tiled.h"
#include "dacpo_cleanup.h"
#include "dacpo_paths.h"

#include "dacpo_ply.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define TILED_CHUNK (1u << 18) /* points per streamed chunk */
#define TILED_MAX_TILES 1000   /* one open file per tile while routing */
#define TILED_MAX_HALO 64
#define ROUTE_BYTES 20 /* uint64 index, 3 float */
#define HALO_BYTES 24  /* uint64 index, 3 float normal, int32 tile */
#define OUT_BYTES DACPO_TILED_OUT_BYTES

static int
fail(char* err, size_t errlen, const char* fmt, ...)
{
  if (err && errlen > 0) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
  }
  return 1;
}

static double
now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int
dacpo_tiled_header_typed(char* buf,
                         size_t len,
                         size_t tiles,
                         uint64_t n,
                         const struct dacpo_ply_rows* rows)
{
  return snprintf(buf,
                  len,
                  "ply\nformat binary_little_endian 1.0\n"
                  "comment pcl_dacpo: normals oriented in %zu tiles\n"
                  "element vertex %llu\nproperty %s x\nproperty %s y\n"
                  "property %s z\nproperty float nx\nproperty float ny\n"
                  "property float nz\nend_header\n",
                  tiles,
                  (unsigned long long)n,
                  rows ? dacpo_ply_rows_type_name(rows, 0) : "float",
                  rows ? dacpo_ply_rows_type_name(rows, 1) : "float",
                  rows ? dacpo_ply_rows_type_name(rows, 2) : "float");
}

void
dacpo_tiled_append_normals(unsigned char* rows,
                           size_t xyz_bytes,
                           const float* nrm,
                           size_t stride,
                           size_t count)
{
  for (size_t i = count; i-- > 0;) { /* from the end: rows grow in place */
    memmove(rows + i * (xyz_bytes + 12), rows + i * xyz_bytes, xyz_bytes);
    memcpy(rows + i * (xyz_bytes + 12) + xyz_bytes, nrm + stride * i, 12);
  }
}

int
dacpo_tiled_header(char* buf, size_t len, size_t tiles, uint64_t n)
{
  return dacpo_tiled_header_typed(buf, len, tiles, n, NULL);
}

uint64_t
dacpo_tiled_sample_stride(uint64_t n)
{
  return n == 0 ? 1 : (n + DACPO_TILED_SAMPLE - 1) / DACPO_TILED_SAMPLE;
}

int
dacpo_tiled_parse_size(const char* text, double* bytes)
{
  char* end = NULL;
  if (!text || !bytes)
    return 0;
  double v = strtod(text, &end);
  if (end == text)
    return 0;
  const char u = *end;
  if (u == 'K' || u == 'k' || u == 'M' || u == 'm' || u == 'G' || u == 'g') {
    v *= u == 'K' || u == 'k' ? 1024.0 : u == 'M' || u == 'm' ? 1048576.0 : 1073741824.0;
    ++end;
  }
  if (*end != '\0' || !(v > 0.0) || !isfinite(v))
    return 0;
  *bytes = v;
  return 1;
}

dacpo_params
dacpo_tiled_params(const dacpo_params* user)
{
  dacpo_params d, p = *user;
  dacpo_params_init(&d);
  p.estimate_normals = 1;
  if (p.weak_edge_fraction == d.weak_edge_fraction)
    p.weak_edge_fraction = DACPO_TILED_WEAK_EDGE_FRACTION;
  return p;
}

uint64_t
dacpo_tiled_points_for_memory(double bytes)
{
  const double p = (bytes - DACPO_TILED_BASE_BYTES) / DACPO_TILED_BYTES_PER_POINT;
  return p < 16.0 ? 16 : (uint64_t)p;
}

typedef struct tiled_run {
  const dacpo_tiled_options* opt;
  dacpo_ply_rows rows;
  FILE* in;
  dacpo_tile_plan* plan;
  size_t T;
  FILE** tile_file;
  uint64_t* tile_count; /* own + halo points per tile */
  uint64_t* own_count;
  char tmp_prefix[4096];
  char out_tmp[4096];
  int out_fd;
  long header_len;
  FILE* halo_file;
  float* chunk;
  int cleanup[3]; /* dacpo_cleanup slots: tile series, halo file, output temp */
} tiled_run;

static void
tile_path(const tiled_run* r, size_t t, char* buf, size_t len)
{
  snprintf(buf, len, "%s.tile%zu", r->tmp_prefix, t);
}

static void
run_cleanup(tiled_run* r, int keep_output)
{
  char path[4200];
  for (int i = 0; i < 3; ++i)
    dacpo_cleanup_drop(r->cleanup[i]);
  if (r->tile_file)
    for (size_t t = 0; t < r->T; ++t) {
      if (r->tile_file[t])
        fclose(r->tile_file[t]);
      tile_path(r, t, path, sizeof(path));
      remove(path);
    }
  if (r->halo_file)
    fclose(r->halo_file);
  snprintf(path, sizeof(path), "%s.halo", r->tmp_prefix);
  remove(path);
  if (r->out_fd >= 0)
    close(r->out_fd);
  if (!keep_output && r->out_tmp[0])
    remove(r->out_tmp);
  if (r->in)
    fclose(r->in);
  dacpo_tile_plan_free(r->plan);
  free(r->tile_file);
  free(r->tile_count);
  free(r->own_count);
  free(r->chunk);
}

/* Pass 1: every point finite, every s-th one into the sample; the plan. */
static int
sample_and_plan(tiled_run* r, char* err, size_t errlen)
{
  const uint64_t n = r->rows.n;
  const uint64_t s = dacpo_tiled_sample_stride(n);
  const size_t m = (size_t)((n + s - 1) / s);
  float* sample = malloc(3 * m * sizeof(float));
  if (!sample)
    return fail(err, errlen, "out of memory for a %zu-point sample", m);
  size_t got = 0;
  for (uint64_t first = 0; first < n; first += TILED_CHUNK) {
    const size_t take = (size_t)(n - first < TILED_CHUNK ? n - first : TILED_CHUNK);
    if (dacpo_ply_rows_read(r->in, &r->rows, first, take, r->chunk, err, errlen) != 0) {
      free(sample);
      return 1;
    }
    for (size_t i = 0; i < take; ++i) {
      const float* p = r->chunk + 3 * i;
      if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
        free(sample);
        return fail(err,
                    errlen,
                    "point %llu of '%s' is not finite (NaN or inf): "
                    "remove such points first",
                    (unsigned long long)(first + i),
                    r->opt->input);
      }
      if ((first + i) % s == 0 && got < m)
        memcpy(sample + 3 * got++, p, 3 * sizeof(float));
    }
  }
  char msg[400];
  const dacpo_status st = dacpo_tile_plan_create(
      sample, got, n, r->opt->max_points, r->opt->halo, &r->plan, msg, sizeof(msg));
  free(sample);
  if (st != DACPO_OK)
    return fail(err, errlen, "%s", msg);
  r->T = dacpo_tile_plan_count(r->plan);
  if (r->T > TILED_MAX_TILES)
    return fail(err,
                errlen,
                "%zu tiles (more than %d files open at once): give more -memory",
                r->T,
                TILED_MAX_TILES);
  return 0;
}

/* Pass 2: index + xyz of every point into its own and its halo tiles' files. */
static int
route(tiled_run* r, dacpo_tiled_report* rep, char* err, size_t errlen)
{
  r->tile_file = calloc(r->T, sizeof(FILE*));
  r->tile_count = calloc(r->T, sizeof(uint64_t));
  r->own_count = calloc(r->T, sizeof(uint64_t));
  if (!r->tile_file || !r->tile_count || !r->own_count)
    return fail(err, errlen, "out of memory for %zu tiles", r->T);
  char path[4200];
  for (size_t t = 0; t < r->T; ++t) {
    tile_path(r, t, path, sizeof(path));
    r->tile_file[t] = fopen(path, "w+b");
    if (!r->tile_file[t])
      return fail(err, errlen, "cannot create '%s': %s", path, strerror(errno));
  }
  const uint64_t n = r->rows.n;
  for (uint64_t first = 0; first < n; first += TILED_CHUNK) {
    const size_t take = (size_t)(n - first < TILED_CHUNK ? n - first : TILED_CHUNK);
    if (dacpo_ply_rows_read(r->in, &r->rows, first, take, r->chunk, err, errlen) != 0)
      return 1;
    for (size_t i = 0; i < take; ++i) {
      int32_t halo[TILED_MAX_HALO];
      size_t nh = 0;
      const int32_t own = dacpo_tile_locate(r->plan, r->chunk + 3 * i, halo, TILED_MAX_HALO, &nh);
      if (nh > TILED_MAX_HALO)
        return fail(err,
                    errlen,
                    "point %llu lies in the halo of %zu tiles (at most %d): the halo "
                    "is too wide for the tile size",
                    (unsigned long long)(first + i),
                    nh,
                    TILED_MAX_HALO);
      unsigned char rec[ROUTE_BYTES];
      const uint64_t idx = first + i;
      memcpy(rec, &idx, 8);
      memcpy(rec + 8, r->chunk + 3 * i, 12);
      r->own_count[own]++;
      for (size_t h = 0; h <= nh; ++h) {
        const int32_t t = h == 0 ? own : halo[h - 1];
        if (fwrite(rec, ROUTE_BYTES, 1, r->tile_file[t]) != 1)
          return fail(err, errlen, "cannot write a tile file: %s", strerror(errno));
        r->tile_count[t]++;
      }
      rep->halo_points += nh;
    }
  }
  for (size_t t = 0; t < r->T; ++t)
    if (r->tile_count[t] > rep->largest_tile)
      rep->largest_tile = r->tile_count[t];
  return 0;
}

static int
write_at(int fd, const void* buf, size_t len, off_t off)
{
  const unsigned char* p = buf;
  while (len > 0) {
    const ssize_t w = pwrite(fd, p, len, off);
    if (w <= 0)
      return -1;
    p += w;
    len -= (size_t)w;
    off += w;
  }
  return 0;
}

static int
read_at(int fd, void* buf, size_t len, off_t off)
{
  unsigned char* p = buf;
  while (len > 0) {
    const ssize_t got = pread(fd, p, len, off);
    if (got <= 0)
      return -1;
    p += got;
    len -= (size_t)got;
    off += got;
  }
  return 0;
}

/* The output's header and its size (points filled in by the tiles). */
static int
create_output(tiled_run* r, char* err, size_t errlen)
{
  if (dacpo_temp_sibling(r->opt->output, "tmp", (long)getpid(), r->out_tmp, sizeof(r->out_tmp)) != 0)
    return fail(err, errlen, "'%s': name too long for a temporary file beside it",
                r->opt->output);
  r->cleanup[2] = dacpo_cleanup_add(r->out_tmp);
  r->out_fd = open(r->out_tmp, O_RDWR | O_CREAT | O_TRUNC, 0644);
  if (r->out_fd < 0)
    return fail(err, errlen, "cannot create '%s': %s", r->out_tmp, strerror(errno));
  char header[512];
  const int len = dacpo_tiled_header(header, sizeof(header), r->T, r->rows.n);
  r->header_len = len;
  if (write_at(r->out_fd, header, (size_t)len, 0) != 0 ||
      ftruncate(r->out_fd, (off_t)len + (off_t)(r->rows.n * OUT_BYTES)) != 0)
    return fail(err, errlen, "cannot write '%s': %s", r->out_tmp, strerror(errno));
  return 0;
}

/* Own points of one tile into the output, consecutive indices in one write. */
static int
write_own(tiled_run* r,
          const uint64_t* idx,
          const float* xyz,
          const float* nrm,
          const uint8_t* own,
          size_t count,
          unsigned char* buf)
{
  size_t i = 0;
  while (i < count) {
    if (!own[i]) {
      ++i;
      continue;
    }
    size_t j = i;
    size_t b = 0;
    while (j < count && own[j] && (j == i || idx[j] == idx[j - 1] + 1) && b < (1u << 20)) {
      memcpy(buf + b, xyz + 3 * j, 12);
      memcpy(buf + b + 12, nrm + 3 * j, 12);
      b += OUT_BYTES;
      ++j;
    }
    if (write_at(r->out_fd, buf, b, (off_t)r->header_len + (off_t)(idx[i] * OUT_BYTES)) != 0)
      return -1;
    i = j;
  }
  return 0;
}

/* Pass 3 for tile t. */
static int
run_tile(tiled_run* r, size_t t, dacpo_ctx* ctx, dacpo_tiled_report* rep, char* err, size_t errlen)
{
  const size_t cnt = (size_t)r->tile_count[t];
  if (cnt == 0)
    return 0;
  uint64_t* idx = malloc(cnt * sizeof(uint64_t));
  float* xyz = malloc(3 * cnt * sizeof(float));
  float* nrm = calloc(3 * cnt, sizeof(float));
  uint8_t* own = malloc(cnt);
  unsigned char* buf = malloc((1u << 20) * OUT_BYTES);
  int rc = 0;
  if (!idx || !xyz || !nrm || !own || !buf)
    rc = fail(err, errlen, "out of memory for tile %zu (%zu points)", t, cnt);
  FILE* f = r->tile_file[t];
  if (rc == 0 && fflush(f) == 0 && fseeko(f, 0, SEEK_SET) == 0) {
    for (size_t i = 0; i < cnt && rc == 0; ++i) {
      unsigned char rec[ROUTE_BYTES];
      if (fread(rec, ROUTE_BYTES, 1, f) != 1)
        rc = fail(err, errlen, "cannot read back tile %zu", t);
      memcpy(&idx[i], rec, 8);
      memcpy(xyz + 3 * i, rec + 8, 12);
      own[i] = dacpo_tile_locate(r->plan, xyz + 3 * i, NULL, 0, NULL) == (int32_t)t;
    }
  }
  else if (rc == 0)
    rc = fail(err, errlen, "cannot read back tile %zu: %s", t, strerror(errno));
  if (rc == 0 && dacpo_orient(ctx, &r->opt->params, NULL, NULL, xyz, nrm, cnt) != DACPO_OK)
    rc = fail(err, errlen, "tile %zu (%zu points): %s", t, cnt, dacpo_ctx_last_error(ctx));
  if (rc == 0) {
    rep->blocks += dacpo_ctx_stats(ctx)->num_blocks;
    if (write_own(r, idx, xyz, nrm, own, cnt, buf) != 0)
      rc = fail(err, errlen, "cannot write '%s': %s", r->out_tmp, strerror(errno));
  }
  for (size_t i = 0; rc == 0 && i < cnt; ++i) {
    if (own[i])
      continue;
    unsigned char rec[HALO_BYTES];
    const int32_t tt = (int32_t)t;
    memcpy(rec, &idx[i], 8);
    memcpy(rec + 8, nrm + 3 * i, 12);
    memcpy(rec + 20, &tt, 4);
    if (fwrite(rec, HALO_BYTES, 1, r->halo_file) != 1)
      rc = fail(err, errlen, "cannot write the halo file: %s", strerror(errno));
  }
  /* the tile's file is done with: free its disk space now */
  char path[4200];
  fclose(r->tile_file[t]);
  r->tile_file[t] = NULL;
  tile_path(r, t, path, sizeof(path));
  remove(path);
  free(idx);
  free(xyz);
  free(nrm);
  free(own);
  free(buf);
  return rc;
}

int
dacpo_tile_pairs_init(dacpo_tile_pairs* m, size_t tiles)
{
  m->used = 0;
  m->cap = 64;
  while (m->cap < 4 * tiles && m->cap < ((size_t)1 << 20))
    m->cap *= 2;
  m->entry = malloc(m->cap * sizeof(dacpo_tile_overlap));
  m->slot = malloc(2 * m->cap * sizeof(int32_t));
  if (m->slot)
    memset(m->slot, 0xff, 2 * m->cap * sizeof(int32_t));
  return m->entry && m->slot;
}

void
dacpo_tile_pairs_free(dacpo_tile_pairs* m)
{
  free(m->entry);
  free(m->slot);
}

static size_t
pair_slot(const dacpo_tile_pairs* m, uint32_t a, uint32_t b)
{
  const uint64_t key = ((uint64_t)a << 32) | b;
  size_t i = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 20) & (2 * m->cap - 1);
  while (m->slot[i] >= 0 && (m->entry[m->slot[i]].a != a || m->entry[m->slot[i]].b != b))
    i = (i + 1) & (2 * m->cap - 1);
  return i;
}

dacpo_tile_overlap*
dacpo_tile_pairs_get(dacpo_tile_pairs* m, uint32_t a, uint32_t b)
{
  size_t i = pair_slot(m, a, b);
  if (m->slot[i] >= 0)
    return &m->entry[m->slot[i]];
  if (m->used == m->cap) { /* grow: twice the entries, rehash */
    dacpo_tile_overlap* e = realloc(m->entry, 2 * m->cap * sizeof(dacpo_tile_overlap));
    int32_t* sl = malloc(4 * m->cap * sizeof(int32_t));
    if (!e || !sl) {
      if (e)
        m->entry = e;
      free(sl);
      return NULL;
    }
    m->entry = e;
    free(m->slot);
    m->slot = sl;
    m->cap *= 2;
    memset(m->slot, 0xff, 2 * m->cap * sizeof(int32_t));
    for (size_t k = 0; k < m->used; ++k)
      m->slot[pair_slot(m, m->entry[k].a, m->entry[k].b)] = (int32_t)k;
    i = pair_slot(m, a, b);
  }
  const dacpo_tile_overlap z = {a, b, 0.0, 0.0};
  m->entry[m->used] = z;
  m->slot[i] = (int32_t)m->used++;
  return &m->entry[m->slot[i]];
}

/* Pass 4: halo normals against their owners' -> evidence -> flips. */
static int
join(tiled_run* r, uint8_t* flip, dacpo_tiled_report* rep, char* err, size_t errlen)
{
  const size_t T = r->T;
  dacpo_tile_pairs ev = {NULL, 0, 0, NULL};
  int rc = dacpo_tile_pairs_init(&ev, T) ? 0 : fail(err, errlen, "out of memory");
  if (rc == 0 && (fflush(r->halo_file) != 0 || fseeko(r->halo_file, 0, SEEK_SET) != 0))
    rc = fail(err, errlen, "cannot read back the halo file");
  unsigned char rec[HALO_BYTES];
  while (rc == 0 && fread(rec, HALO_BYTES, 1, r->halo_file) == 1) {
    uint64_t idx;
    float n[3], o[6];
    int32_t t;
    memcpy(&idx, rec, 8);
    memcpy(n, rec + 8, 12);
    memcpy(&t, rec + 20, 4);
    if (read_at(r->out_fd, o, sizeof(o), (off_t)r->header_len + (off_t)(idx * OUT_BYTES)) != 0) {
      rc = fail(err, errlen, "cannot read back '%s'", r->out_tmp);
      break;
    }
    const int32_t owner = dacpo_tile_locate(r->plan, o, NULL, 0, NULL);
    if (owner < 0 || (size_t)owner >= T || t < 0 || (size_t)t >= T) {
      rc = fail(err, errlen, "internal: halo record of point %llu", (unsigned long long)idx);
      break;
    }
    const double d = (double)n[0] * o[3] + (double)n[1] * o[4] + (double)n[2] * o[5];
    dacpo_tile_overlap* e = dacpo_tile_pairs_get(&ev, (uint32_t)t, (uint32_t)owner);
    if (!e) {
      rc = fail(err, errlen, "out of memory");
      break;
    }
    if (d >= 0.0)
      e->same += fabs(d);
    else
      e->opposite += fabs(d);
  }
  char msg[400];
  if (rc == 0 &&
      dacpo_tile_join(T, ev.entry, ev.used, r->own_count, flip, msg, sizeof(msg)) != DACPO_OK)
    rc = fail(err, errlen, "%s", msg);
  for (size_t t = 0; rc == 0 && t < T; ++t)
    rep->flipped_tiles += flip[t];
  dacpo_tile_pairs_free(&ev);
  return rc;
}

/* Pass 5: negate the normals of points whose tile is flipped. */
static int
apply_flips(tiled_run* r, const uint8_t* flip, char* err, size_t errlen)
{
  size_t any = 0;
  for (size_t t = 0; t < r->T; ++t)
    any += flip[t];
  if (!any)
    return 0;
  const uint64_t n = r->rows.n;
  float* buf = (float*)r->chunk; /* 3 floats per point: room for half a chunk */
  const size_t per = TILED_CHUNK / 2;
  for (uint64_t first = 0; first < n; first += per) {
    const size_t take = (size_t)(n - first < per ? n - first : per);
    const off_t off = (off_t)r->header_len + (off_t)(first * OUT_BYTES);
    if (read_at(r->out_fd, buf, take * OUT_BYTES, off) != 0)
      return fail(err, errlen, "cannot read back '%s'", r->out_tmp);
    for (size_t i = 0; i < take; ++i) {
      float* rec = buf + 6 * i;
      if (flip[dacpo_tile_locate(r->plan, rec, NULL, 0, NULL)])
        for (int k = 3; k < 6; ++k)
          rec[k] = -rec[k];
    }
    if (write_at(r->out_fd, buf, take * OUT_BYTES, off) != 0)
      return fail(err, errlen, "cannot write '%s': %s", r->out_tmp, strerror(errno));
  }
  return 0;
}

/* Coordinates not exact in float (double input): the output is written again
 * with the input's x y z bytes and the normals of the float file. */
static int
rewrite_exact(tiled_run* r, const char* path, char* err, size_t errlen)
{
  const size_t xb = dacpo_ply_rows_xyz_bytes(&r->rows);
  char header[600];
  const int hl = dacpo_tiled_header_typed(header, sizeof(header), r->T, r->rows.n, &r->rows);
  FILE* out = fopen(path, "wb");
  const size_t per = TILED_CHUNK / 2;
  unsigned char* raw = malloc(per * (xb + 12));
  float* rec = (float*)r->chunk; /* 6 floats per point: room for half a chunk */
  int rc = out && raw && hl > 0 && fwrite(header, (size_t)hl, 1, out) == 1 ? 0 : -1;
  for (uint64_t first = 0; rc == 0 && first < r->rows.n; first += per) {
    const size_t take = (size_t)(r->rows.n - first < per ? r->rows.n - first : per);
    rc = read_at(r->out_fd, rec, take * OUT_BYTES,
                 (off_t)r->header_len + (off_t)(first * OUT_BYTES));
    rc = rc == 0 ? dacpo_ply_rows_read_raw(r->in, &r->rows, first, take, raw, err, errlen) : rc;
    if (rc == 0)
      dacpo_tiled_append_normals(raw, xb, rec + 3, 6, take);
    if (rc == 0 && fwrite(raw, xb + 12, take, out) != take)
      rc = -1;
  }
  if (out && (fflush(out) != 0 || fsync(fileno(out)) != 0))
    rc = -1;
  if (out && fclose(out) != 0)
    rc = -1;
  free(raw);
  if (rc != 0)
    remove(path);
  return rc != 0 ? fail(err, errlen, "cannot write '%s': %s", path, strerror(errno)) : 0;
}

/* Sync the output and rename it onto the user's name. */
static int
finish_output(tiled_run* r, char* err, size_t errlen)
{
  const char* done = r->out_tmp;
  char exact[4200];
  int slot = -1;
  if (fsync(r->out_fd) != 0)
    return fail(err, errlen, "cannot write '%s': %s", r->out_tmp, strerror(errno));
  if (!dacpo_ply_rows_exact_in_float(&r->rows)) {
    if (dacpo_temp_sibling(r->opt->output, "exact", (long)getpid(), exact, sizeof(exact)) != 0)
      return fail(err, errlen, "'%s': name too long for a temporary file", r->opt->output);
    slot = dacpo_cleanup_add(exact);
    if (rewrite_exact(r, exact, err, errlen) != 0) {
      dacpo_cleanup_drop(slot);
      return -1;
    }
    done = exact;
  }
  const int renamed = rename(done, r->opt->output) == 0;
  const int saved = errno;
  if (slot >= 0) /* the float file is done with; the exact one if not renamed */
    remove(renamed ? r->out_tmp : exact);
  dacpo_cleanup_drop(slot);
  if (!renamed)
    return fail(err, errlen, "cannot rename onto '%s': %s", r->opt->output, strerror(saved));
  return 0;
}

/* The prefix of the tile and halo files: beside the output unless told
 * otherwise; the longest tile name and the output's temporary sibling must fit. */
static int
temp_prefix(tiled_run* r, char* err, size_t errlen)
{
  const dacpo_tiled_options* opt = r->opt;
  char dir[3900];
  if (opt->tmp_dir)
    snprintf(dir, sizeof(dir), "%s", opt->tmp_dir);
  else {
    snprintf(dir, sizeof(dir), "%s", opt->output);
    char* slash = strrchr(dir, '/');
    if (slash)
      *slash = '\0';
    else
      snprintf(dir, sizeof(dir), ".");
  }
  const int len =
      snprintf(r->tmp_prefix, sizeof(r->tmp_prefix), "%s/.dacpo%ld", dir, (long)getpid());
  char probe[4096];
  if (len <= 0 || (size_t)len + 32 > sizeof(r->tmp_prefix) ||
      dacpo_temp_sibling(opt->output, "tmp", (long)getpid(), probe, sizeof(probe)) != 0)
    return fail(err, errlen, "'%s': name too long for temporary files beside it", opt->output);
  return 0;
}

int
dacpo_tiled_orient(const dacpo_tiled_options* opt,
                   dacpo_tiled_report* rep,
                   char* err,
                   size_t errlen)
{
  if (!opt || !rep || !opt->input || !opt->output)
    return fail(err, errlen, "dacpo_tiled_orient: NULL argument");
  const uint32_t probe = 1;
  unsigned char first_byte;
  memcpy(&first_byte, &probe, 1);
  if (first_byte != 1)
    return fail(err, errlen, "tiles write little-endian PLY: not on a big-endian host");
  memset(rep, 0, sizeof(*rep));
  tiled_run r;
  memset(&r, 0, sizeof(r));
  r.opt = opt;
  r.out_fd = -1;
  r.cleanup[0] = r.cleanup[1] = r.cleanup[2] = -1;
  r.chunk = malloc(3 * (size_t)TILED_CHUNK * sizeof(float) * 2);
  if (!r.chunk)
    return fail(err, errlen, "out of memory");
  if (temp_prefix(&r, err, errlen) != 0) {
    free(r.chunk);
    return -1;
  }
  double t0 = now_s();
  int rc = dacpo_ply_rows_open(opt->input, &r.rows, err, errlen) != 0;
  if (rc == 0 && r.rows.n == 0)
    rc = fail(err, errlen, "'%s' has no points", opt->input);
  if (rc == 0 && !(r.in = fopen(opt->input, "rb")))
    rc = fail(err, errlen, "cannot open '%s': %s", opt->input, strerror(errno));
  if (rc == 0)
    rc = dacpo_ply_rows_set_origin(r.in, &r.rows, err, errlen) != 0;
  if (rc == 0)
    rc = sample_and_plan(&r, err, errlen);
  rep->points = r.rows.n;
  rep->tiles = r.T;
  rep->halo = dacpo_tile_plan_halo(r.plan);
  double t1 = now_s();
  rep->seconds[0] = t1 - t0;
  if (rc == 0)
    r.cleanup[0] = dacpo_cleanup_add_series(r.tmp_prefix, r.T);
  if (rc == 0)
    rc = route(&r, rep, err, errlen);
  if (rc == 0)
    rc = create_output(&r, err, errlen);
  char path[4200];
  snprintf(path, sizeof(path), "%s.halo", r.tmp_prefix);
  r.cleanup[1] = dacpo_cleanup_add(path);
  if (rc == 0 && !(r.halo_file = fopen(path, "w+b")))
    rc = fail(err, errlen, "cannot create '%s': %s", path, strerror(errno));
  t0 = now_s();
  rep->seconds[1] = t0 - t1;
  dacpo_ctx* ctx = NULL;
  if (rc == 0 && dacpo_ctx_create(&ctx) != DACPO_OK)
    rc = fail(err, errlen, "out of memory");
  for (size_t t = 0; rc == 0 && t < r.T; ++t)
    rc = run_tile(&r, t, ctx, rep, err, errlen);
  dacpo_ctx_free(ctx);
  t1 = now_s();
  rep->seconds[2] = t1 - t0;
  uint8_t* flip = calloc(r.T ? r.T : 1, 1);
  if (rc == 0 && !flip)
    rc = fail(err, errlen, "out of memory");
  if (rc == 0)
    rc = join(&r, flip, rep, err, errlen);
  t0 = now_s();
  rep->seconds[3] = t0 - t1;
  if (rc == 0)
    rc = apply_flips(&r, flip, err, errlen);
  free(flip);
  if (rc == 0)
    rc = finish_output(&r, err, errlen);
  rep->seconds[4] = now_s() - t0;
  run_cleanup(&r, rc == 0);
  return rc;
}
