/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Minimal PLY reader and writer for point clouds with normals (dacpo_ply.h).
 * This file reads; the writer is in dacpo_ply_write.c, and reading a binary
 * file's vertex rows in parts (dacpo_ply_rows_*) in dacpo_ply_rows.c.
 *
 * Reader: parses the header (elements, scalar and list properties, the three
 * formats), skips the elements before "vertex", then decodes the vertex rows
 * through a small buffered reader. Before allocating, the declared vertex count
 * is checked against the bytes left in the file, so a corrupt header cannot ask
 * for an absurd allocation; running out of data is reported as truncation.
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

#define PLY_MAX_LINE 1024
#define PLY_MAX_HEADER_LINES 4096

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

/* One header line without its terminator ("\n" or "\r\n").
 * Returns 0, -1 at end of file, -2 when the line is too long. */
static int
in_line(ply_in* in, char* line, size_t cap)
{
  size_t k = 0;
  int c;
  for (;;) {
    c = in_getc(in);
    if (c < 0)
      return -1;
    if (c == '\n')
      break;
    if (k + 1 >= cap)
      return -2;
    line[k++] = (char)c;
  }
  if (k > 0 && line[k - 1] == '\r')
    --k;
  line[k] = '\0';
  return 0;
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

/* ------------------------------------------------------------------------- */
/* Header model.                                                              */

static ply_type
parse_type(const char* s)
{
  static const struct {
    const char* name;
    ply_type type;
  } names[] = {{"char", T_I8},
               {"int8", T_I8},
               {"uchar", T_U8},
               {"uint8", T_U8},
               {"short", T_I16},
               {"int16", T_I16},
               {"ushort", T_U16},
               {"uint16", T_U16},
               {"int", T_I32},
               {"int32", T_I32},
               {"uint", T_U32},
               {"uint32", T_U32},
               {"float", T_F32},
               {"float32", T_F32},
               {"double", T_F64},
               {"float64", T_F64}};
  for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); ++i)
    if (strcmp(s, names[i].name) == 0)
      return names[i].type;
  return T_NONE;
}

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

static int
prop_role(const char* name)
{
  static const char* const roles[6] = {"x", "y", "z", "nx", "ny", "nz"};
  for (int i = 0; i < 6; ++i)
    if (strcmp(name, roles[i]) == 0)
      return i;
  return -1;
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

/* Parse an unsigned decimal count; -1 on anything else. */
static int
parse_count(const char* s, uint64_t* out)
{
  char* end;
  unsigned long long v;
  if (!s || *s < '0' || *s > '9')
    return -1;
  errno = 0;
  v = strtoull(s, &end, 10);
  if (errno != 0 || *end != '\0')
    return -1;
  *out = (uint64_t)v;
  return 0;
}

/* Split s in place at spaces and tabs; at most max words (the rest is ignored,
 * extra words only make a line invalid through the callers' count checks). */
static int
split_words(char* s, char** words, int max)
{
  int n = 0;
  while (*s) {
    while (*s == ' ' || *s == '\t')
      *s++ = '\0';
    if (!*s)
      break;
    if (n == max)
      return n + 1;
    words[n++] = s;
    while (*s && *s != ' ' && *s != '\t')
      ++s;
  }
  return n;
}

/* A "format" line: ascii, binary_little_endian or binary_big_endian. */
static int
header_format(ply_header* h, char** tok, int nt, int lineno, char* err, size_t errlen)
{
  if (nt < 2 || (strcmp(tok[1], "ascii") && strcmp(tok[1], "binary_little_endian") &&
                 strcmp(tok[1], "binary_big_endian"))) {
    dacpo_support_err(err,
                      errlen,
                      "unsupported PLY format '%s' (line %d)",
                      nt > 1 ? tok[1] : "",
                      lineno);
    return DACPO_PLY_ERR_FORMAT;
  }
  h->format = strcmp(tok[1], "ascii") == 0                  ? FMT_ASCII
              : strcmp(tok[1], "binary_little_endian") == 0 ? FMT_BLE
                                                            : FMT_BBE;
  return DACPO_PLY_OK;
}

/* An "element name count" line: a new element. */
static int
header_element(ply_header* h, char** tok, int nt, int lineno, char* err, size_t errlen)
{
  ply_element* e;
  if (nt != 3) {
    dacpo_support_err(err, errlen, "bad element line %d", lineno);
    return DACPO_PLY_ERR_FORMAT;
  }
  if (h->nel >= PLY_MAX_ELEMENTS) {
    dacpo_support_err(
        err, errlen, "more than %d elements in the PLY header", PLY_MAX_ELEMENTS);
    return DACPO_PLY_ERR_FORMAT;
  }
  e = &h->el[h->nel++];
  memset(e, 0, sizeof(*e));
  snprintf(e->name, sizeof(e->name), "%s", tok[1]);
  if (parse_count(tok[2], &e->count) != 0) {
    dacpo_support_err(err,
                      errlen,
                      "bad count '%s' for element '%s' (line %d)",
                      tok[2],
                      e->name,
                      lineno);
    return DACPO_PLY_ERR_FORMAT;
  }
  return DACPO_PLY_OK;
}

/* A "property type name" or "property list count_type type name" line: a
 * property of the last element. */
static int
header_property(ply_header* h, char** tok, int nt, int lineno, char* err, size_t errlen)
{
  ply_element* e = h->nel > 0 ? &h->el[h->nel - 1] : NULL;
  ply_prop* p;
  if (!e) {
    dacpo_support_err(err, errlen, "property before any element (line %d)", lineno);
    return DACPO_PLY_ERR_FORMAT;
  }
  if (e->nprops >= PLY_MAX_PROPS) {
    dacpo_support_err(
        err, errlen, "more than %d properties in element '%s'", PLY_MAX_PROPS, e->name);
    return DACPO_PLY_ERR_FORMAT;
  }
  p = &e->props[e->nprops];
  if (nt == 5 && strcmp(tok[1], "list") == 0) {
    p->count_type = parse_type(tok[2]);
    p->type = parse_type(tok[3]);
    p->role = -1;
    if (p->count_type == T_NONE || p->count_type == T_F32 || p->count_type == T_F64 ||
        p->type == T_NONE) {
      dacpo_support_err(err, errlen, "bad list property types on line %d", lineno);
      return DACPO_PLY_ERR_FORMAT;
    }
  }
  else if (nt == 3) {
    p->count_type = T_NONE;
    p->type = parse_type(tok[1]);
    p->role = prop_role(tok[2]);
    if (p->type == T_NONE) {
      dacpo_support_err(
          err, errlen, "unknown property type '%s' on line %d", tok[1], lineno);
      return DACPO_PLY_ERR_FORMAT;
    }
  }
  else {
    dacpo_support_err(err, errlen, "bad property line %d", lineno);
    return DACPO_PLY_ERR_FORMAT;
  }
  e->nprops++;
  return DACPO_PLY_OK;
}

static int
read_header(ply_in* in, ply_header* h, char* err, size_t errlen)
{
  char line[PLY_MAX_LINE];
  int have_format = 0;
  int rc = in_line(in, line, sizeof(line));
  if (rc != 0 || strcmp(line, "ply") != 0) {
    dacpo_support_err(err, errlen, "not a PLY file (first line is not 'ply')");
    return DACPO_PLY_ERR_FORMAT;
  }
  for (int lineno = 2; lineno < PLY_MAX_HEADER_LINES; ++lineno) {
    char* tok[6] = {NULL, NULL, NULL, NULL, NULL, NULL};
    int nt = 0;
    int status;
    rc = in_line(in, line, sizeof(line));
    if (rc == -1) {
      dacpo_support_err(err, errlen, "PLY header ends before 'end_header'");
      return DACPO_PLY_ERR_FORMAT;
    }
    if (rc == -2) {
      dacpo_support_err(err,
                        errlen,
                        "PLY header line %d is longer than %d bytes",
                        lineno,
                        PLY_MAX_LINE - 1);
      return DACPO_PLY_ERR_FORMAT;
    }
    if (strncmp(line, "comment", 7) == 0 || strncmp(line, "obj_info", 8) == 0)
      continue;
    nt = split_words(line, tok, 6);
    if (nt == 0)
      continue;
    if (strcmp(tok[0], "end_header") == 0) {
      if (!have_format) {
        dacpo_support_err(err, errlen, "PLY header has no 'format' line");
        return DACPO_PLY_ERR_FORMAT;
      }
      return DACPO_PLY_OK;
    }
    if (strcmp(tok[0], "format") == 0) {
      status = header_format(h, tok, nt, lineno, err, errlen);
      have_format = 1;
    }
    else if (strcmp(tok[0], "element") == 0)
      status = header_element(h, tok, nt, lineno, err, errlen);
    else if (strcmp(tok[0], "property") == 0)
      status = header_property(h, tok, nt, lineno, err, errlen);
    else {
      dacpo_support_err(
          err, errlen, "unknown PLY header keyword '%s' on line %d", tok[0], lineno);
      status = DACPO_PLY_ERR_FORMAT;
    }
    if (status != DACPO_PLY_OK)
      return status;
  }
  dacpo_support_err(
      err, errlen, "PLY header longer than %d lines", PLY_MAX_HEADER_LINES);
  return DACPO_PLY_ERR_FORMAT;
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
  status = read_header(in, h, err, errlen);
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
