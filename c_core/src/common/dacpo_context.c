/* SPDX-License-Identifier: BSD-3-Clause */
/* Context, error text, status strings, parameter defaults and validation, and
 * the small utilities every stage uses (RNG, clock, checked allocation). */
#define _POSIX_C_SOURCE 200809L
#include "dacpo_context.h"

#include <dacpo/dacpo_param_table.h>

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

const char*
dacpo_version_string(void)
{
  return "0.1.0";
}

const char*
dacpo_status_string(dacpo_status status)
{
  switch (status) {
  case DACPO_OK:
    return "ok";
  case DACPO_ERR_INVALID_ARGUMENT:
    return "invalid argument";
  case DACPO_ERR_EMPTY_INPUT:
    return "empty input";
  case DACPO_ERR_NONFINITE_INPUT:
    return "non-finite or zero-length input value";
  case DACPO_ERR_TOO_FEW_POINTS:
    return "too few distinct points";
  case DACPO_ERR_DISCONNECTED:
    return "neighbour graph is disconnected";
  case DACPO_ERR_NEIGHBOR_SEARCH:
    return "neighbour search failed";
  case DACPO_ERR_SOLVER:
    return "0-1 program solver failed";
  case DACPO_ERR_OUT_OF_MEMORY:
    return "out of memory";
  case DACPO_ERR_CANCELLED:
    return "cancelled";
  case DACPO_ERR_INTERNAL:
    return "internal error";
  }
  return "unknown status";
}

const char*
dacpo_stage_name(dacpo_stage stage)
{
  static const char* const names[DACPO_STAGE_COUNT] = {"input",
                                                       "neighbors",
                                                       "normals",
                                                       "segment",
                                                       "dipole",
                                                       "ipsr",
                                                       "edge_weights",
                                                       "ilp",
                                                       "mesh"};
  if ((int)stage < 0 || stage >= DACPO_STAGE_COUNT)
    return "unknown";
  return names[stage];
}

void
dacpo_params_init(dacpo_params* p)
{
  if (!p)
    return;
  memset(p, 0, sizeof(*p)); /* viewpoint (0, 0, 0) */
  /* every default from the one table (dacpo_param_table.h) */
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc) p->name = def;
  DACPO_PARAMS()
#undef DACPO_PARAM
}

static dacpo_status
bad_field(char* message, size_t size, const char* fmt, ...)
{
  if (message && size > 0) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, size, fmt, ap);
    va_end(ap);
  }
  return DACPO_ERR_INVALID_ARGUMENT;
}

/* The names dacpo_params_set takes for each enum field, in value order. */
static const char* const names_edge_weight[] = {"dipole", "vcr", "overlap"};
static const char* const names_disconnected[] = {"separate", "error", "bridge", "viewpoint"};
static const char* const names_sign_policy[] = {"free_space", "viewpoint", "keep"};
static const char* const names_scan_kind[] = {"auto", "single", "multi"};

/* Whole-text integer in [lo, hi]. */
static int
parse_integer(const char* text, long long lo, unsigned long long hi, unsigned long long* out)
{
  if (!text || !*text || isspace((unsigned char)*text))
    return 0;
  char* end = NULL;
  errno = 0;
  if (text[0] == '-') {
    const long long v = strtoll(text, &end, 10);
    if (errno || *end || v < lo)
      return 0;
    *out = (unsigned long long)v;
    return 1;
  }
  const unsigned long long v = strtoull(text, &end, 10);
  if (errno || *end || v > hi)
    return 0;
  *out = v;
  return 1;
}

static int
parse_real(const char* text, double* out)
{
  if (!text || !*text || isspace((unsigned char)*text))
    return 0;
  char* end = NULL;
  *out = strtod(text, &end);
  return *end == '\0' && isfinite(*out);
}

static int
parse_name(const char* text, const char* const* names, size_t count, int* out)
{
  for (size_t i = 0; text && i < count; ++i)
    if (strcmp(text, names[i]) == 0) {
      *out = (int)i;
      return 1;
    }
  return 0;
}

/* One field's parse by the table's kind: 1 when value fits, into tmp. */
#define DACPO_SET_SIZE(name)                                                   \
  (parse_integer(value, 0, SIZE_MAX, &u) && ((tmp.name = (size_t)u), 1))
#define DACPO_SET_U64(name)                                                    \
  (parse_integer(value, 0, UINT64_MAX, &u) && ((tmp.name = (uint64_t)u), 1))
#define DACPO_SET_UINT(name)                                                   \
  (parse_integer(value, 0, UINT_MAX, &u) && ((tmp.name = (unsigned)u), 1))
#define DACPO_SET_INT(name)                                                    \
  (parse_integer(value, INT_MIN, INT_MAX, &u) && ((tmp.name = (int)(long long)u), 1))
#define DACPO_SET_FLAG(name)                                                   \
  (parse_integer(value, 0, 1, &u) && ((tmp.name = (int)u), 1))
#define DACPO_SET_REAL(name) parse_real(value, &tmp.name)
#define DACPO_SET_ENUM(name)                                                   \
  (parse_name(value,                                                           \
              names_##name,                                                    \
              sizeof(names_##name) / sizeof(names_##name[0]),                  \
              &e) &&                                                           \
   ((tmp.name = e), 1))

dacpo_status
dacpo_params_set(dacpo_params* params,
                 const char* name,
                 const char* value,
                 char* message,
                 size_t message_size)
{
  if (!params || !name || !value)
    return bad_field(message, message_size, "dacpo_params_set: NULL argument");
  dacpo_params tmp = *params;
  unsigned long long u = 0;
  int e = 0;
#define DACPO_PARAM(kind, type, field, def, lo, hi, who, cli, flag, doc)                     \
  if (strcmp(name, #field) == 0) {                                             \
    if (!(DACPO_SET_##kind(field)))                                            \
      return bad_field(message,                                                \
                       message_size,                                           \
                       "%s: '%s' is not a value it takes",                     \
                       name,                                                   \
                       value);                                                 \
    *params = tmp;                                                             \
    return DACPO_OK;                                                           \
  }
  DACPO_PARAMS()
#undef DACPO_PARAM
  return bad_field(message, message_size, "no parameter is called '%s'", name);
}

/* Every field within its row's [min, max] (dacpo_param_table.h); a real
 * also finite. An enum's range is its values. */
static dacpo_status
check_ranges(const dacpo_params* p, char* message, size_t size)
{
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc)       \
  {                                                                            \
    const double v = (double)p->name;                                          \
    if (!(v >= (double)(lo) && v <= (double)(hi)) || !isfinite(v))             \
      return strcmp(#kind, "ENUM") == 0                                        \
                 ? bad_field(message, size, #name " has an unknown value %d",  \
                             (int)p->name)                                     \
                 : bad_field(message, size, #name " must be in [%g, %g] (got %g)", \
                             (double)(lo), (double)(hi), v);                   \
  }
  DACPO_PARAMS()
#undef DACPO_PARAM
  return DACPO_OK;
}

/* What a range cannot say. */
static dacpo_status
check_special(const dacpo_params* p, char* message, size_t size)
{
  if (p->dipole_c >= 0.0 && p->dipole_c < 1.0)
    return bad_field(message,
                     size,
                     "dipole_c must be >= 1 (paper Eq. 1), or negative for the scan "
                     "kind's value (got %g)",
                     p->dipole_c);
  if (p->sign_policy == DACPO_SIGN_VIEWPOINT &&
      !(isfinite(p->viewpoint[0]) && isfinite(p->viewpoint[1]) &&
        isfinite(p->viewpoint[2])))
    return bad_field(message, size, "viewpoint must be finite");
  return DACPO_OK;
}

dacpo_status
dacpo_params_validate(const dacpo_params* p, char* message, size_t size)
{
  if (message && size > 0)
    message[0] = '\0';
  if (!p)
    return bad_field(message, size, "params is NULL");
  DACPO_TRY(check_ranges(p, message, size));
  return check_special(p, message, size);
}

dacpo_status
dacpo_err_set(dacpo_err* err, dacpo_status code, const char* fmt, ...)
{
  if (err) {
    err->code = code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof(err->msg), fmt, ap);
    va_end(ap);
  }
  return code;
}

/* ---- context ----------------------------------------------------------- */

dacpo_status
dacpo_ctx_create(dacpo_ctx** out)
{
  if (!out)
    return DACPO_ERR_INVALID_ARGUMENT;
  *out = calloc(1, sizeof(dacpo_ctx));
  return *out ? DACPO_OK : DACPO_ERR_OUT_OF_MEMORY;
}

void
dacpo_ctx_clear_results(dacpo_ctx* ctx)
{
  free(ctx->point_component);
  free(ctx->point_block);
  free(ctx->point_curvature);
  free(ctx->point_confidence);
  free(ctx->block_flips);
  free(ctx->edges);
  free(ctx->mesh_vertices);
  free(ctx->mesh_triangles);
  ctx->mesh_vertices = NULL;
  ctx->mesh_triangles = NULL;
  ctx->mesh_num_vertices = 0;
  ctx->mesh_num_triangles = 0;
  ctx->point_component = NULL;
  ctx->point_block = NULL;
  ctx->point_curvature = NULL;
  ctx->point_confidence = NULL;
  ctx->block_flips = NULL;
  ctx->edges = NULL;
  memset(&ctx->stats, 0, sizeof(ctx->stats));
}

void
dacpo_ctx_free(dacpo_ctx* ctx)
{
  if (!ctx)
    return;
  dacpo_ctx_clear_results(ctx);
  free(ctx);
}

dacpo_status
dacpo_ctx_fail(dacpo_ctx* ctx, const dacpo_err* err)
{
  snprintf(ctx->last_error, sizeof(ctx->last_error), "%s", err->msg);
  return err->code;
}

const char*
dacpo_ctx_last_error(const dacpo_ctx* ctx)
{
  return ctx ? ctx->last_error : "context is NULL";
}

const dacpo_stats*
dacpo_ctx_stats(const dacpo_ctx* ctx)
{
  return ctx ? &ctx->stats : NULL;
}

const int32_t*
dacpo_ctx_point_components(const dacpo_ctx* ctx)
{
  return ctx ? ctx->point_component : NULL;
}

const int32_t*
dacpo_ctx_point_blocks(const dacpo_ctx* ctx)
{
  return ctx ? ctx->point_block : NULL;
}

const float*
dacpo_ctx_point_curvature(const dacpo_ctx* ctx)
{
  return ctx ? ctx->point_curvature : NULL;
}

const float*
dacpo_ctx_point_confidence(const dacpo_ctx* ctx)
{
  return ctx ? ctx->point_confidence : NULL;
}

size_t
dacpo_ctx_mesh(const dacpo_ctx* ctx,
               const float** vertices,
               size_t* num_vertices,
               const int32_t** triangles)
{
  if (vertices)
    *vertices = ctx ? ctx->mesh_vertices : NULL;
  if (num_vertices)
    *num_vertices = ctx ? ctx->mesh_num_vertices : 0;
  if (triangles)
    *triangles = ctx ? ctx->mesh_triangles : NULL;
  return ctx ? ctx->mesh_num_triangles : 0;
}

const uint8_t*
dacpo_ctx_block_flips(const dacpo_ctx* ctx)
{
  return ctx ? ctx->block_flips : NULL;
}

const dacpo_edge_info*
dacpo_ctx_edges(const dacpo_ctx* ctx)
{
  return ctx ? ctx->edges : NULL;
}

/* ---- utilities --------------------------------------------------------- */

double
dacpo_now(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void
dacpo_mesh_free(dacpo_mesh* mesh)
{
  if (!mesh)
    return;
  free(mesh->vertices);
  free(mesh->triangles);
  memset(mesh, 0, sizeof(*mesh));
}

void*
dacpo_malloc_array(size_t count, size_t size)
{
  if (size != 0 && count > SIZE_MAX / size)
    return NULL;
  size_t bytes = count * size;
  return malloc(bytes != 0 ? bytes : 1);
}

void*
dacpo_calloc_array(size_t count, size_t size)
{
  if (size != 0 && count > SIZE_MAX / size)
    return NULL;
  return calloc(count ? count : 1, size ? size : 1);
}

int
dacpo_cmp_double(const void* a, const void* b)
{
  const double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

/* Quickselect: the k-th smallest of v[0..n) (v is permuted). */
double
dacpo_select_kth(double* v, size_t n, size_t k)
{
  size_t lo = 0, hi = n - 1;
  while (lo < hi) {
    double pivot = v[lo + (hi - lo) / 2];
    size_t i = lo, j = hi;
    while (i <= j) {
      while (v[i] < pivot)
        ++i;
      while (v[j] > pivot)
        --j;
      if (i <= j) {
        double t = v[i];
        v[i] = v[j];
        v[j] = t;
        ++i;
        if (j == 0)
          break;
        --j;
      }
    }
    if (k <= j)
      hi = j;
    else if (k >= i)
      lo = i;
    else
      break;
  }
  return v[k];
}
