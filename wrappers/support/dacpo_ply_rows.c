/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Reading the vertex rows of a binary PLY in parts (dacpo_ply_rows_*, see
 * dacpo_ply.h): the header is parsed by dacpo_ply.c (dacpo_ply_open_vertices),
 * then any range of rows is read at its file offset and decoded here.
 */
#define _FILE_OFFSET_BITS 64
#define _POSIX_C_SOURCE 200809L
#include "dacpo_ply.h"

#include "dacpo_ply_internal.h"
#include "dacpo_support_err.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

int
dacpo_ply_rows_open(const char* path, dacpo_ply_rows* out, char* err, size_t errlen)
{
  ply_in in;
  ply_header h;
  ply_element* vert = NULL;
  int has_normals = 0;
  if (err && errlen > 0)
    err[0] = '\0';
  if (!path || !out) {
    dacpo_support_err(err, errlen, "dacpo_ply_rows_open: NULL argument");
    return DACPO_PLY_ERR_ARGUMENT;
  }
  memset(out, 0, sizeof(*out));
  int status = dacpo_ply_open_vertices(path, &in, &h, &vert, &has_normals, err, errlen);
  if (status == DACPO_PLY_OK && h.format == FMT_ASCII) {
    dacpo_support_err(err,
                      errlen,
                      "'%s' is ASCII PLY: reading it in parts needs binary PLY "
                      "(convert it first, e.g. pcl_dacpo_orient writes binary PLY)",
                      path);
    status = DACPO_PLY_ERR_FORMAT;
  }
  for (int j = 0; status == DACPO_PLY_OK && j < vert->nprops; ++j)
    if (vert->props[j].count_type != T_NONE) {
      dacpo_support_err(
          err, errlen, "'%s': the vertex element has a list property: rows differ in size", path);
      status = DACPO_PLY_ERR_FORMAT;
    }
  if (status == DACPO_PLY_OK) {
    out->n = vert->count;
    out->data_offset = in.consumed;
    out->swap = h.format == FMT_BBE;
    size_t off = 0;
    for (int j = 0; j < vert->nprops; ++j) {
      const ply_prop* pr = &vert->props[j];
      if (pr->role >= 0 && pr->role < 3) {
        out->offset[pr->role] = off;
        out->type[pr->role] = (int)pr->type;
      }
      off += dacpo_ply_type_size(pr->type);
    }
    out->stride = off;
  }
  dacpo_ply_close(&in, &h);
  return status;
}

/* Calls emit(rows, row, i, user) for the rows [first, first + count) of f. */
static int
rows_walk(FILE* f,
          const dacpo_ply_rows* rows,
          unsigned long long first,
          size_t count,
          void (*emit)(const dacpo_ply_rows*, const unsigned char*, size_t, void*),
          void* user,
          char* err,
          size_t errlen)
{
  if (!f || !rows || (!user && count > 0) || first > rows->n || count > rows->n - first) {
    dacpo_support_err(err, errlen, "dacpo_ply_rows_read: bad argument or range");
    return DACPO_PLY_ERR_ARGUMENT;
  }
  unsigned char buf[PLY_BUF_SIZE];
  const size_t per = PLY_BUF_SIZE / rows->stride;
  if (per == 0 || fseeko(f, (off_t)(rows->data_offset + first * rows->stride), SEEK_SET) != 0) {
    dacpo_support_err(err, errlen, "cannot seek to vertex %llu", first);
    return DACPO_PLY_ERR_IO;
  }
  for (size_t done = 0; done < count;) {
    const size_t take = count - done < per ? count - done : per;
    if (fread(buf, rows->stride, take, f) != take) {
      dacpo_support_err(err, errlen, "short read at vertex %llu", first + done);
      return DACPO_PLY_ERR_IO;
    }
    for (size_t i = 0; i < take; ++i)
      emit(rows, buf + i * rows->stride, done + i, user);
    done += take;
  }
  return DACPO_PLY_OK;
}

static void
emit_float(const dacpo_ply_rows* rows, const unsigned char* row, size_t i, void* user)
{
  float* xyz = (float*)user;
  for (int k = 0; k < 3; ++k)
    xyz[3 * i + (size_t)k] =
        (float)(dacpo_ply_decode(
                    row + rows->offset[k], (ply_type)rows->type[k], rows->swap) -
                rows->origin[k]);
}

static void
emit_double(const dacpo_ply_rows* rows, const unsigned char* row, size_t i, void* user)
{
  double* xyz = (double*)user;
  for (int k = 0; k < 3; ++k)
    xyz[3 * i + (size_t)k] =
        dacpo_ply_decode(row + rows->offset[k], (ply_type)rows->type[k], rows->swap);
}

static void
emit_raw(const dacpo_ply_rows* rows, const unsigned char* row, size_t i, void* user)
{
  unsigned char* out = (unsigned char*)user + i * dacpo_ply_rows_xyz_bytes(rows);
  for (int k = 0; k < 3; ++k) {
    const size_t sz = dacpo_ply_type_size((ply_type)rows->type[k]);
    for (size_t b = 0; b < sz; ++b) /* little-endian, as the output is */
      *out++ = row[rows->offset[k] + (rows->swap ? sz - 1 - b : b)];
  }
}

int
dacpo_ply_rows_read(FILE* f,
                    const dacpo_ply_rows* rows,
                    unsigned long long first,
                    size_t count,
                    float* xyz,
                    char* err,
                    size_t errlen)
{
  return rows_walk(f, rows, first, count, emit_float, xyz, err, errlen);
}

int
dacpo_ply_rows_read_double(FILE* f,
                           const dacpo_ply_rows* rows,
                           unsigned long long first,
                           size_t count,
                           double* xyz,
                           char* err,
                           size_t errlen)
{
  return rows_walk(f, rows, first, count, emit_double, xyz, err, errlen);
}

int
dacpo_ply_rows_read_raw(FILE* f,
                        const dacpo_ply_rows* rows,
                        unsigned long long first,
                        size_t count,
                        unsigned char* out,
                        char* err,
                        size_t errlen)
{
  return rows_walk(f, rows, first, count, emit_raw, out, err, errlen);
}

size_t
dacpo_ply_rows_xyz_bytes(const dacpo_ply_rows* rows)
{
  size_t b = 0;
  for (int k = 0; k < 3; ++k)
    b += dacpo_ply_type_size((ply_type)rows->type[k]);
  return b;
}

int
dacpo_ply_rows_exact_in_float(const dacpo_ply_rows* rows)
{
  return dacpo_ply_exact_in_float((ply_type)rows->type[0]) &&
         dacpo_ply_exact_in_float((ply_type)rows->type[1]) &&
         dacpo_ply_exact_in_float((ply_type)rows->type[2]);
}

const char*
dacpo_ply_rows_type_name(const dacpo_ply_rows* rows, int k)
{
  static const char* const names[] = {"float", "char", "uchar", "short", "ushort",
                                      "int",   "uint", "float", "double"};
  const int t = rows->type[k];
  return t >= 0 && t < (int)(sizeof(names) / sizeof(names[0])) ? names[t] : "float";
}

int
dacpo_ply_rows_set_origin(FILE* f, dacpo_ply_rows* rows, char* err, size_t errlen)
{
  double p[3] = {0.0, 0.0, 0.0};
  if (rows->n > 0 && !dacpo_ply_rows_exact_in_float(rows)) {
    const int rc = dacpo_ply_rows_read_double(f, rows, 0, 1, p, err, errlen);
    if (rc != DACPO_PLY_OK)
      return rc;
  }
  memcpy(rows->origin, p, sizeof(p));
  return DACPO_PLY_OK;
}
