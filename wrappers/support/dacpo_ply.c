/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Minimal PLY reader and writer for point clouds with normals (dacpo_ply.h).
 * This file reads; the writer is in dacpo_ply_write.c, and reading a binary
 * file's vertex rows in parts (dacpo_ply_rows_*) in dacpo_ply_rows.c.
 *
 * Reader: parses the header (dacpo_ply_header.c: elements, scalar and list
 * properties, the three formats), skips the elements before "vertex", then
 * decodes the vertex rows through a small buffered reader. Before allocating,
 * the declared vertex count is checked against the bytes left in the file, so
 * a corrupt header cannot ask for an absurd allocation; running out of data is
 * reported as truncation.
 *
 * Cost: O(file size) time, 12 or 24 bytes per point of memory.
 * Failure modes: see the DACPO_PLY_ERR_* codes; never crashes.
 */
#define _FILE_OFFSET_BITS 64
#define _POSIX_C_SOURCE 200809L
#include "dacpo_ply.h"

#include "dacpo_ply_internal.h"
#include "dacpo_support_err.h"

#include <errno.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------- */
/* Buffered input.                                                            */

static int
in_fill(ply_in* in)
{
  if (in->eof)
    return 0;
  if (in->pos < in->len)
    memmove(in->buf, in->buf + in->pos, in->len - in->pos);
  in->len -= in->pos;
  in->pos = 0;
  {
    const size_t got = fread(in->buf + in->len, 1, PLY_BUF_SIZE - in->len, in->f);
    if (got == 0)
      in->eof = 1;
    in->len += got;
    return got > 0;
  }
}

/* Next byte, or -1 at end of file. */
static int
in_getc(ply_in* in)
{
  if (in->pos >= in->len && !in_fill(in))
    return -1;
  in->consumed++;
  return in->buf[in->pos++];
}

/* Copy len (<= PLY_BUF_SIZE) bytes to dst; -1 when the file ends first. */
static int
in_read(ply_in* in, unsigned char* dst, size_t len)
{
  if (in->len - in->pos < len) {
    while (in->len - in->pos < len && in_fill(in)) {
    }
    if (in->len - in->pos < len)
      return -1;
  }
  memcpy(dst, in->buf + in->pos, len);
  in->pos += len;
  in->consumed += len;
  return 0;
}

static int
in_skip(ply_in* in, uint64_t len)
{
  unsigned char tmp[256];
  while (len > 0) {
    const size_t step = len > sizeof(tmp) ? sizeof(tmp) : (size_t)len;
    if (in_read(in, tmp, step) != 0)
      return -1;
    len -= step;
  }
  return 0;
}

/* One header line without its terminator ("\n" or "\r\n"; the last line of
 * the file may have none), cut to cap - 1 bytes (the rest of a longer line is
 * skipped). Returns 0, -1 at end of file, -3 when the line holds a NUL byte. */
static int
in_line(ply_in* in, char* line, size_t cap)
{
  size_t k = 0, got = 0;
  int c, nul = 0;
  for (;;) {
    c = in_getc(in);
    if (c < 0 && got == 0)
      return -1;
    if (c < 0 || c == '\n')
      break;
    ++got;
    nul |= c == '\0';
    if (k + 1 < cap)
      line[k++] = (char)c;
  }
  if (k > 0 && line[k - 1] == '\r')
    --k;
  line[k] = '\0';
  return nul ? -3 : 0;
}

/* Next whitespace-separated ASCII token; -1 at end of file, -2 when too long,
 * -3 when the line ended and !first (an ASCII row is one line: a token may
 * not come from the next line, or every later point would shift). */
static int
in_token(ply_in* in, char* tok, size_t cap, int first)
{
  size_t k = 0;
  int c;
  if (in->eol && !first)
    return -3;
  do {
    c = in_getc(in);
    if (c == '\n' && !first)
      return -3;
  } while (c == ' ' || c == '\t' || c == '\n' || c == '\r');
  if (c < 0)
    return -1;
  while (c >= 0 && c != ' ' && c != '\t' && c != '\n' && c != '\r') {
    if (k + 1 >= cap)
      return -2;
    tok[k++] = (char)c;
    c = in_getc(in);
  }
  in->eol = c == '\n' || c < 0;
  tok[k] = '\0';
  return 0;
}

/* After the last value of an ASCII row: only blanks up to the line's end
 * (0), or -3 when the row holds more values than the header declares. */
static int
in_row_end(ply_in* in)
{
  int c = 0;
  while (!in->eol && (c = in_getc(in)) != '\n' && c >= 0)
    if (c != ' ' && c != '\t' && c != '\r')
      return -3;
  in->eol = 0;
  return 0;
}

int
dacpo_ply_in_line(ply_in* in, char* line, size_t cap)
{
  return in_line(in, line, cap);
}

/* ------------------------------------------------------------------------- */
/* Types.                                                                     */

size_t
dacpo_ply_type_size(ply_type t)
{
  switch (t) {
  case T_I8:
  case T_U8:
    return 1;
  case T_I16:
  case T_U16:
    return 2;
  case T_I32:
  case T_U32:
  case T_F32:
    return 4;
  case T_F64:
    return 8;
  case T_NONE:
    break;
  }
  return 0;
}

/* 1 when a value of type t converts to float exactly. */
int
dacpo_ply_exact_in_float(ply_type t)
{
  return t != T_F64 && t != T_I32 && t != T_U32;
}

/* Decode one binary value of type t at p (swap = file is big-endian). */
double
dacpo_ply_decode(const unsigned char* p, ply_type t, int swap)
{
  unsigned char b[8];
  const size_t sz = dacpo_ply_type_size(t);
  for (size_t i = 0; i < sz; ++i)
    b[i] = swap ? p[sz - 1 - i] : p[i];
  /* From here b holds the little-endian bytes; assemble portably. */
  switch (t) {
  case T_I8:
    return (double)(int8_t)b[0];
  case T_U8:
    return (double)b[0];
  case T_I16:
  case T_U16: {
    const uint16_t u = (uint16_t)(b[0] | (b[1] << 8));
    return t == T_I16 ? (double)(int16_t)u : (double)u;
  }
  case T_I32:
  case T_U32:
  case T_F32: {
    const uint32_t u = (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) |
                       ((uint32_t)b[3] << 24);
    if (t == T_F32) {
      float f;
      memcpy(&f, &u, sizeof(f));
      return (double)f;
    }
    return t == T_I32 ? (double)(int32_t)u : (double)u;
  }
  case T_F64: {
    uint64_t u = 0;
    double d;
    for (int i = 7; i >= 0; --i)
      u = (u << 8) | b[i];
    memcpy(&d, &u, sizeof(d));
    return d;
  }
  case T_NONE:
    break;
  }
  return 0.0;
}

/* ------------------------------------------------------------------------- */
/* Data.                                                                      */

/* One value of type t: binary via the buffer, ASCII via a token. */
static int
read_value(ply_in* in, int format, ply_type t, double* v, int first)
{
  if (format == FMT_ASCII) {
    char tok[128];
    char* end;
    const int rc = in_token(in, tok, sizeof(tok), first);
    if (rc != 0)
      return rc == -3 ? -3 : -1;
    *v = strtod(tok, &end);
    return *end == '\0' ? 0 : -2;
  }
  {
    unsigned char b[8];
    if (in_read(in, b, dacpo_ply_type_size(t)) != 0)
      return -1;
    *v = dacpo_ply_decode(b, t, format == FMT_BBE);
    return 0;
  }
}

/* Read one row of element e; roles 0..5 go to vals[role]. */
static int
read_row(ply_in* in, int format, const ply_element* e, double vals[6])
{
  for (int j = 0; j < e->nprops; ++j) {
    const ply_prop* p = &e->props[j];
    double v;
    int rc;
    if (p->count_type != T_NONE) {
      double cnt;
      rc = read_value(in, format, p->count_type, &cnt, j == 0);
      if (rc != 0)
        return rc;
      if (!(cnt >= 0.0) || cnt > 4294967295.0 || cnt != (double)(uint64_t)cnt)
        return -2;
      if (format == FMT_ASCII) {
        for (uint64_t k = 0; k < (uint64_t)cnt; ++k)
          if ((rc = read_value(in, format, p->type, &v, 0)) != 0)
            return rc;
      }
      else if (in_skip(in, (uint64_t)cnt * dacpo_ply_type_size(p->type)) != 0) {
        return -1;
      }
      continue;
    }
    rc = read_value(in, format, p->type, &v, j == 0);
    if (rc != 0)
      return rc;
    if (p->role >= 0)
      vals[p->role] = v;
  }
  return format == FMT_ASCII ? in_row_end(in) : 0;
}

/* Smallest number of bytes one row can take (lists counted as empty). */
static uint64_t
min_row_bytes(int format, const ply_element* e)
{
  uint64_t s = 0;
  for (int j = 0; j < e->nprops; ++j) {
    const ply_prop* p = &e->props[j];
    if (format == FMT_ASCII)
      s += 2; /* a digit and a separator */
    else
      s += dacpo_ply_type_size(p->count_type != T_NONE ? p->count_type : p->type);
  }
  return s;
}

/* The vertex element of the header, with x, y and z; *has_normals if it also
 * has nx, ny and nz. */
static int
find_vertex(const ply_header* h,
            const char* path,
            ply_element** vert,
            int* has_normals,
            char* err,
            size_t errlen)
{
  int has_role[6] = {0, 0, 0, 0, 0, 0};
  *vert = NULL;
  for (int i = 0; i < h->nel && !*vert; ++i)
    if (strcmp(h->el[i].name, "vertex") == 0)
      *vert = &h->el[i];
  if (!*vert) {
    dacpo_support_err(err, errlen, "'%s' has no 'vertex' element", path);
    return DACPO_PLY_ERR_FORMAT;
  }
  for (int j = 0; j < (*vert)->nprops; ++j)
    if ((*vert)->props[j].role >= 0)
      has_role[(*vert)->props[j].role] = 1;
  if (!has_role[0] || !has_role[1] || !has_role[2]) {
    dacpo_support_err(err, errlen, "'%s': vertex element lacks x, y or z", path);
    return DACPO_PLY_ERR_FORMAT;
  }
  *has_normals = has_role[3] && has_role[4] && has_role[5];
  return DACPO_PLY_OK;
}

/* Skips the elements stored before the vertices (each checked against the
 * bytes left of the fsize-byte file first). */
static int
skip_elements_before(ply_in* in,
                     const ply_header* h,
                     const ply_element* vert,
                     long fsize,
                     const char* path,
                     char* err,
                     size_t errlen)
{
  for (const ply_element* e = h->el; e != vert; ++e) {
    double dummy[6];
    if (e->nprops == 0) /* its rows hold nothing, however many it declares */
      continue;
    const uint64_t left = (uint64_t)fsize - in->consumed;
    const uint64_t row = min_row_bytes(h->format, e);
    if (row > 0 && e->count > left / row) {
      dacpo_support_err(err,
                        errlen,
                        "'%s' is truncated: element '%s' declares %llu rows",
                        path,
                        e->name,
                        (unsigned long long)e->count);
      return DACPO_PLY_ERR_FORMAT;
    }
    for (uint64_t i = 0; i < e->count; ++i) {
      const int rc = read_row(in, h->format, e, dummy);
      if (rc != 0) {
        dacpo_support_err(err,
                          errlen,
                          "'%s': %s in element '%s' row %llu",
                          path,
                          rc == -1   ? "unexpected end of file"
                          : rc == -3 ? "a row with more or fewer values than its properties"
                                     : "bad value",
                          e->name,
                          (unsigned long long)i);
        return DACPO_PLY_ERR_FORMAT;
      }
    }
  }
  return DACPO_PLY_OK;
}

/* The vertex count must fit in the bytes left: this rejects corrupt counts
 * before any allocation. */
static int
check_vertex_count(const ply_in* in,
                   int format,
                   const ply_element* vert,
                   long fsize,
                   const char* path,
                   char* err,
                   size_t errlen)
{
  const uint64_t left = (uint64_t)fsize - in->consumed;
  const uint64_t row = min_row_bytes(format, vert);
  uint64_t need_ok = row == 0 ? (vert->count == 0) : (vert->count <= left / row);
  if (format == FMT_ASCII && vert->count > 0 && row > 0)
    need_ok = vert->count <= (left + 1) / row; /* last row may lack its newline */
  if (!need_ok || vert->count > (uint64_t)(SIZE_MAX / (6 * sizeof(float)))) {
    dacpo_support_err(
        err,
        errlen,
        "'%s' is truncated: header declares %llu vertices (at least %llu bytes) "
        "but only %llu bytes of data follow",
        path,
        (unsigned long long)vert->count,
        (unsigned long long)(vert->count * row),
        (unsigned long long)left);
    return DACPO_PLY_ERR_FORMAT;
  }
  return DACPO_PLY_OK;
}

/* 1 when x, y or z of vert has a type float cannot hold exactly. */
static int
vertex_needs_double(const ply_element* vert)
{
  for (int j = 0; j < vert->nprops; ++j)
    if (vert->props[j].role >= 0 && vert->props[j].role < 3 &&
        !dacpo_ply_exact_in_float(vert->props[j].type))
      return 1;
  return 0;
}

/* Decodes the vertex rows into c (positions, and normals if has_normals);
 * with exact, coordinates float cannot hold go to c->xyz_exact as read and
 * to c->xyz as offsets from vertex 0 (c->origin). */
static int
read_vertices(ply_in* in,
              int format,
              const ply_element* vert,
              int has_normals,
              int exact,
              dacpo_ply_cloud* c,
              const char* path,
              char* err,
              size_t errlen)
{
  c->n = (size_t)vert->count;
  exact = exact && vertex_needs_double(vert);
  if (c->n > 0) {
    c->xyz = (float*)malloc(3 * c->n * sizeof(float));
    if (has_normals)
      c->normals = (float*)malloc(3 * c->n * sizeof(float));
    if (exact)
      c->xyz_exact = (double*)malloc(3 * c->n * sizeof(double));
    if (!c->xyz || (has_normals && !c->normals) || (exact && !c->xyz_exact)) {
      dacpo_support_err(err, errlen, "out of memory reading %zu vertices", c->n);
      return DACPO_PLY_ERR_MEMORY;
    }
  }
  for (size_t i = 0; i < c->n; ++i) {
    double v[6] = {0, 0, 0, 0, 0, 0};
    const int rc = read_row(in, format, vert, v);
    if (rc != 0) {
      dacpo_support_err(err,
                        errlen,
                        "'%s': %s at vertex %zu of %zu",
                        path,
                        rc == -1   ? "unexpected end of file (truncated)"
                        : rc == -3 ? "a row with more or fewer values than the header's properties"
                                   : "bad value",
                        i,
                        c->n);
      return DACPO_PLY_ERR_FORMAT;
    }
    if (exact && i == 0)
      memcpy(c->origin, v, sizeof(c->origin));
    for (int k = 0; k < 3; ++k) {
      c->xyz[3 * i + (size_t)k] = (float)(v[k] - c->origin[k]);
      if (exact)
        c->xyz_exact[3 * i + (size_t)k] = v[k];
    }
    if (has_normals)
      for (int k = 0; k < 3; ++k)
        c->normals[3 * i + (size_t)k] = (float)v[3 + k];
  }
  return DACPO_PLY_OK;
}

/* Opens path and finds its size (a regular file is needed for the size
 * checks). */
static int
open_sized(const char* path, ply_in* in, long* fsize, char* err, size_t errlen)
{
  in->f = fopen(path, "rb");
  if (!in->f) {
    dacpo_support_err(err, errlen, "cannot open '%s': %s", path, strerror(errno));
    return DACPO_PLY_ERR_IO;
  }
  if (fseek(in->f, 0, SEEK_END) != 0 || (*fsize = ftell(in->f)) < 0 ||
      fseek(in->f, 0, SEEK_SET) != 0) {
    dacpo_support_err(
        err, errlen, "cannot determine the size of '%s' (not a regular file?)", path);
    fclose(in->f);
    return DACPO_PLY_ERR_IO;
  }
  return DACPO_PLY_OK;
}

/* Opens path and reads up to its first vertex row: the header, the vertex
 * element (*vert, *has_normals), the elements before it, the count check. On
 * success in->f is open at vertex 0 and in->buf, h->el are allocated; on failure
 * as much as was opened, which dacpo_ply_close() releases either way. */
int
dacpo_ply_open_vertices(const char* path,
                        ply_in* in,
                        ply_header* h,
                        ply_element** vert,
                        int* has_normals,
                        char* err,
                        size_t errlen)
{
  long fsize = 0;
  memset(in, 0, sizeof(*in));
  memset(h, 0, sizeof(*h));
  int status = open_sized(path, in, &fsize, err, errlen);
  if (status != DACPO_PLY_OK) {
    in->f = NULL;
    return status;
  }
  in->buf = (unsigned char*)malloc(PLY_BUF_SIZE);
  h->el = (ply_element*)malloc(PLY_MAX_ELEMENTS * sizeof(ply_element));
  if (!in->buf || !h->el) {
    dacpo_support_err(err, errlen, "out of memory");
    return DACPO_PLY_ERR_MEMORY;
  }
  /* each step runs only if the ones before succeeded */
  status = dacpo_ply_parse_header(in, h, path, err, errlen);
  if (status == DACPO_PLY_OK)
    status = find_vertex(h, path, vert, has_normals, err, errlen);
  if (status == DACPO_PLY_OK)
    status = skip_elements_before(in, h, *vert, fsize, path, err, errlen);
  if (status == DACPO_PLY_OK)
    status = check_vertex_count(in, h->format, *vert, fsize, path, err, errlen);
  return status;
}

void
dacpo_ply_close(ply_in* in, ply_header* h)
{
  free(h->el);
  free(in->buf);
  if (in->f)
    fclose(in->f);
}

static int
ply_read(const char* path, int exact, dacpo_ply_cloud* out, char* err, size_t errlen);

int
dacpo_ply_read(const char* path, dacpo_ply_cloud* out, char* err, size_t errlen)
{
  return ply_read(path, 0, out, err, errlen);
}

int
dacpo_ply_read_exact(const char* path, dacpo_ply_cloud* out, char* err, size_t errlen)
{
  return ply_read(path, 1, out, err, errlen);
}

static int
ply_read(const char* path, int exact, dacpo_ply_cloud* out, char* err, size_t errlen)
{
  ply_in in;
  ply_header h;
  ply_element* vert = NULL;
  int has_normals = 0;
  dacpo_ply_cloud c;

  if (err && errlen > 0)
    err[0] = '\0';
  if (out)
    memset(out, 0, sizeof(*out));
  if (!path || !out) {
    dacpo_support_err(
        err, errlen, "dacpo_ply_read: %s is NULL", !path ? "path" : "out");
    return DACPO_PLY_ERR_ARGUMENT;
  }
  memset(&c, 0, sizeof(c));
  int status = dacpo_ply_open_vertices(path, &in, &h, &vert, &has_normals, err, errlen);
  if (status == DACPO_PLY_OK)
    status = read_vertices(&in, h.format, vert, has_normals, exact, &c, path, err, errlen);
  if (status == DACPO_PLY_OK && ferror(in.f)) {
    dacpo_support_err(err, errlen, "read error on '%s'", path);
    status = DACPO_PLY_ERR_IO;
  }
  if (status == DACPO_PLY_OK) {
    *out = c;
    memset(&c, 0, sizeof(c));
  }
  dacpo_ply_cloud_free(&c);
  dacpo_ply_close(&in, &h);
  return status;
}

void
dacpo_ply_cloud_free(dacpo_ply_cloud* cloud)
{
  if (!cloud)
    return;
  free(cloud->xyz);
  free(cloud->normals);
  free(cloud->xyz_exact);
  memset(cloud, 0, sizeof(*cloud));
}
