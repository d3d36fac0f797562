/* SPDX-License-Identifier: BSD-3-Clause */
/* PCD input/output (see dacpo_pcd.h). The header is parsed by
 * dacpo_pcd_header.c; the point records are then either whitespace-separated
 * text (ascii), packed little-endian records of the fields in header order
 * (binary) or those LZF-compressed field by field (binary_compressed). */
#include "dacpo_pcd.h"

#include "dacpo_support_err.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define PCD_MAX_POINTS ((size_t)1 << 34) /* beyond any file this tool can hold */

int
dacpo_is_pcd_path(const char* path)
{
  size_t len = path ? strlen(path) : 0;
  return len >= 4 && strcasecmp(path + len - 4, ".pcd") == 0;
}

int
dacpo_is_ply_path(const char* path)
{
  size_t len = path ? strlen(path) : 0;
  return len >= 4 && strcasecmp(path + len - 4, ".ply") == 0;
}

/* The header (dacpo_pcd_read_header) and what this reader needs of it: the
 * number of points (POINTS, or WIDTH x HEIGHT), x, y and z, float coordinates
 * and normals of 4 or 8 bytes; finds x, y, z and the normals (idx[0..5], -1
 * when absent). */
static int
read_header(FILE* fp,
            const char* path,
            dacpo_pcd_header* h,
            int idx[6],
            char* err,
            size_t errlen)
{
  if (dacpo_pcd_read_header(fp, path, h, err, errlen) != DACPO_PLY_OK)
    return 0;
  if (!h->have_points) {
    if (!h->have_width) {
      dacpo_support_err(err, errlen, "'%s': neither POINTS nor WIDTH is given", path);
      return 0;
    }
    h->points = h->width * (h->have_height ? h->height : 1);
  }
  if (h->points > PCD_MAX_POINTS) {
    dacpo_support_err(
        err, errlen, "'%s': %zu points is more than supported", path, h->points);
    return 0;
  }
  static const char* names[6] = {"x", "y", "z", "normal_x", "normal_y", "normal_z"};
  for (int k = 0; k < 6; ++k)
    idx[k] = -1;
  for (int i = 0; i < h->nf; ++i)
    for (int k = 0; k < 6; ++k)
      if (!strcmp(h->f[i].name, names[k]) && idx[k] < 0)
        idx[k] = i;
  if (idx[0] < 0 || idx[1] < 0 || idx[2] < 0) {
    dacpo_support_err(err, errlen, "'%s': the fields x, y and z are required", path);
    return 0;
  }
  if ((idx[3] >= 0) + (idx[4] >= 0) + (idx[5] >= 0) != 3)
    idx[3] = idx[4] = idx[5] = -1; /* partial normals: positions only */
  for (int k = 0; k < 6; ++k)
    if (idx[k] >= 0 && h->f[idx[k]].type == 'F' && h->f[idx[k]].size != 4 &&
        h->f[idx[k]].size != 8) {
      dacpo_support_err(err,
                        errlen,
                        "'%s': field %s is a float of %d bytes",
                        path,
                        names[k],
                        h->f[idx[k]].size);
      return 0;
    }
  return 1;
}

/* The first value of field f in a binary record, as float. */
static float
binary_value(const unsigned char* rec, const dacpo_pcd_field* f)
{
  const unsigned char* p = rec + f->offset;
  uint64_t u = 0;
  for (int b = f->size - 1; b >= 0; --b) /* little-endian */
    u = (u << 8) | p[b];
  if (f->type == 'F') {
    if (f->size == 8) {
      double d;
      memcpy(&d, &u, 8);
      return (float)d;
    }
    uint32_t w = (uint32_t)u;
    float v;
    memcpy(&v, &w, 4);
    return v;
  }
  if (f->type == 'U')
    return (float)u;
  const int shift = 64 - 8 * f->size; /* sign-extend */
  return (float)((int64_t)(u << shift) >> shift);
}

/* Value k of point i: x, y, z, then normal_x, normal_y, normal_z. */
static void
store(dacpo_ply_cloud* out, size_t i, int k, float x)
{
  if (k < 3)
    out->xyz[3 * i + (size_t)k] = x;
  else if (out->normals)
    out->normals[3 * i + (size_t)(k - 3)] = x;
}

static int
read_binary(FILE* fp,
            const char* path,
            const dacpo_pcd_header* h,
            const int idx[6],
            dacpo_ply_cloud* out,
            char* err,
            size_t errlen)
{
  unsigned char* rec = malloc(h->record ? h->record : 1);
  if (!rec) {
    dacpo_support_err(err, errlen, "out of memory");
    return DACPO_PLY_ERR_MEMORY;
  }
  for (size_t i = 0; i < h->points; ++i) {
    if (fread(rec, 1, h->record, fp) != h->record) {
      free(rec);
      dacpo_support_err(
          err, errlen, "'%s' is truncated: %zu of %zu points", path, i, h->points);
      return DACPO_PLY_ERR_FORMAT;
    }
    for (int k = 0; k < 6; ++k)
      if (idx[k] >= 0)
        store(out, i, k, binary_value(rec, &h->f[idx[k]]));
  }
  free(rec);
  return DACPO_PLY_OK;
}

/* LZF (the compression of PCL's DATA binary_compressed): a control byte c < 32
 * starts a run of c + 1 literal bytes; otherwise it is a back reference of
 * length (c >> 5) + 2 (a length field of 7 continues in the next byte) at
 * distance ((c & 31) << 8 | next byte) + 1. Returns the bytes written, or 0 if
 * the stream is corrupt or does not fill out exactly. */
static size_t
lzf_decode(const unsigned char* in, size_t in_len, unsigned char* out, size_t out_len)
{
  size_t i = 0, o = 0;
  while (i < in_len) {
    const unsigned c = in[i++];
    if (c < 32) {
      const size_t run = (size_t)c + 1;
      if (run > in_len - i || run > out_len - o)
        return 0;
      memcpy(out + o, in + i, run);
      i += run;
      o += run;
      continue;
    }
    size_t len = c >> 5;
    if (len == 7) {
      if (i >= in_len)
        return 0;
      len += in[i++];
    }
    len += 2;
    if (i >= in_len)
      return 0;
    const size_t dist = (((size_t)c & 31) << 8 | in[i++]) + 1;
    if (dist > o || len > out_len - o)
      return 0;
    for (size_t k = 0; k < len; ++k, ++o) /* may overlap: byte by byte */
      out[o] = out[o - dist];
  }
  return o == out_len ? o : 0;
}

static long
bytes_left(FILE* fp);

/* DATA binary_compressed: two little-endian uint32 sizes, then LZF data that
 * expands to the fields one after another (all points' x, then all y, ...). */
static int
read_compressed(FILE* fp,
                const char* path,
                const dacpo_pcd_header* h,
                const int idx[6],
                dacpo_ply_cloud* out,
                char* err,
                size_t errlen)
{
  unsigned char sz[8];
  if (fread(sz, 1, 8, fp) != 8) {
    dacpo_support_err(err, errlen, "'%s' is truncated: no compressed data", path);
    return DACPO_PLY_ERR_FORMAT;
  }
  const size_t csize =
      (size_t)sz[0] | (size_t)sz[1] << 8 | (size_t)sz[2] << 16 | (size_t)sz[3] << 24;
  const size_t usize =
      (size_t)sz[4] | (size_t)sz[5] << 8 | (size_t)sz[6] << 16 | (size_t)sz[7] << 24;
  if (usize != h->points * h->record) {
    dacpo_support_err(err,
                      errlen,
                      "'%s': the compressed data expands to %zu bytes, not the %zu "
                      "of %zu points",
                      path,
                      usize,
                      h->points * h->record,
                      h->points);
    return DACPO_PLY_ERR_FORMAT;
  }
  const long left = bytes_left(fp);
  if (left < 0 || csize > (size_t)left) {
    dacpo_support_err(err,
                      errlen,
                      "'%s' is truncated: %zu compressed bytes announced, %ld left",
                      path,
                      csize,
                      left);
    return DACPO_PLY_ERR_FORMAT;
  }
  unsigned char* c = malloc(csize ? csize : 1);
  unsigned char* u = malloc(usize ? usize : 1);
  int rc = DACPO_PLY_OK;
  if (!c || !u) {
    dacpo_support_err(err, errlen, "out of memory");
    rc = DACPO_PLY_ERR_MEMORY;
  }
  else if (fread(c, 1, csize, fp) != csize) {
    dacpo_support_err(err, errlen, "'%s' is truncated: compressed data", path);
    rc = DACPO_PLY_ERR_FORMAT;
  }
  else if (usize && lzf_decode(c, csize, u, usize) != usize) {
    dacpo_support_err(err, errlen, "'%s': corrupt compressed data", path);
    rc = DACPO_PLY_ERR_FORMAT;
  }
  for (size_t i = 0; rc == DACPO_PLY_OK && i < h->points; ++i)
    for (int k = 0; k < 6; ++k) {
      if (idx[k] < 0)
        continue;
      /* a field's block starts at points x its offset in a record */
      const dacpo_pcd_field* f = &h->f[idx[k]];
      dacpo_pcd_field at = *f;
      at.offset = 0;
      const unsigned char* v =
          u + h->points * f->offset + i * (size_t)f->size * f->count;
      const float x = binary_value(v, &at);
      store(out, i, k, x);
    }
  free(c);
  free(u);
  return rc;
}

static int
read_ascii(FILE* fp,
           const char* path,
           const dacpo_pcd_header* h,
           const int idx[6],
           dacpo_ply_cloud* out,
           char* err,
           size_t errlen)
{
  /* value position of each field's first value on a line */
  size_t first[DACPO_PCD_MAX_FIELDS], total = 0;
  for (int f = 0; f < h->nf; ++f) {
    first[f] = total;
    total += h->f[f].count;
  }
  for (size_t i = 0; i < h->points; ++i) {
    for (size_t v = 0; v < total; ++v) {
      char word[128];
      if (fscanf(fp, "%127s", word) != 1) {
        dacpo_support_err(
            err, errlen, "'%s' is truncated: %zu of %zu points", path, i, h->points);
        return DACPO_PLY_ERR_FORMAT;
      }
      const int after = fgetc(fp); /* a word longer than the buffer is no number */
      char* end = NULL;
      const float x = strtof(word, &end);
      if (*end != '\0' || (after != EOF && !isspace(after))) {
        dacpo_support_err(
            err, errlen, "'%s': point %zu: '%s' is not a number", path, i, word);
        return DACPO_PLY_ERR_FORMAT;
      }
      for (int k = 0; k < 6; ++k)
        if (idx[k] >= 0 && first[idx[k]] == v)
          store(out, i, k, x);
    }
  }
  char word[16]; /* a value left over: some line had one too many */
  if (fscanf(fp, "%15s", word) == 1) {
    dacpo_support_err(
        err, errlen, "'%s': values after the last of %zu points", path, h->points);
    return DACPO_PLY_ERR_FORMAT;
  }
  return DACPO_PLY_OK;
}

/* The data the header announces can be in the rest of the file: a header that
 * claims billions of points over a few bytes is refused before any allocation
 * (binary: a full record per point; ascii: at least two characters per value;
 * compressed: LZF expands at most 88-fold, a 3-byte reference to 264 bytes). */
static long
bytes_left(FILE* fp)
{
  const long here = ftell(fp);
  if (here < 0 || fseek(fp, 0, SEEK_END) != 0)
    return -1;
  const long end = ftell(fp);
  if (end < here || fseek(fp, here, SEEK_SET) != 0)
    return -1;
  return end - here;
}

static int
fits_file(
    FILE* fp, const char* path, const dacpo_pcd_header* h, char* err, size_t errlen)
{
  const long left = bytes_left(fp);
  if (left < 0) {
    dacpo_support_err(err, errlen, "'%s': cannot measure the file", path);
    return 0;
  }
  const double rest = (double)left;
  size_t values = 0;
  for (int f = 0; f < h->nf; ++f)
    values += h->f[f].count;
  const double need = !strcmp(h->data, "binary") ? (double)h->points * (double)h->record
                      : !strcmp(h->data, "ascii")
                          ? (double)h->points * (double)values * 2.0 - 1.0
                          : (double)h->points * (double)h->record / 88.0;
  if (need > rest) {
    dacpo_support_err(
        err,
        errlen,
        "'%s' is truncated: %zu points need more than the %.0f bytes left",
        path,
        h->points,
        rest);
    return 0;
  }
  return 1;
}

int
dacpo_pcd_read(const char* path, dacpo_ply_cloud* out, char* err, size_t errlen)
{
  if (!out || !path) {
    dacpo_support_err(err, errlen, "NULL argument");
    return DACPO_PLY_ERR_ARGUMENT;
  }
  memset(out, 0, sizeof(*out));
  FILE* fp = fopen(path, "rb");
  if (!fp) {
    dacpo_support_err(err, errlen, "cannot open '%s': %s", path, strerror(errno));
    return DACPO_PLY_ERR_IO;
  }
  dacpo_pcd_header h;
  int idx[6];
  int rc = DACPO_PLY_ERR_FORMAT;
  if (read_header(fp, path, &h, idx, err, errlen) &&
      fits_file(fp, path, &h, err, errlen)) {
    const size_t n = h.points;
    out->n = n;
    out->xyz = n ? malloc(3 * n * sizeof(float)) : NULL;
    out->normals = n && idx[3] >= 0 ? malloc(3 * n * sizeof(float)) : NULL;
    if (n && (!out->xyz || (idx[3] >= 0 && !out->normals))) {
      dacpo_support_err(err, errlen, "out of memory for %zu points", n);
      rc = DACPO_PLY_ERR_MEMORY;
    }
    else
      rc = !strcmp(h.data, "binary") ? read_binary(fp, path, &h, idx, out, err, errlen)
           : !strcmp(h.data, "ascii")
               ? read_ascii(fp, path, &h, idx, out, err, errlen)
               : read_compressed(fp, path, &h, idx, out, err, errlen);
  }
  fclose(fp);
  if (rc != DACPO_PLY_OK)
    dacpo_ply_cloud_free(out);
  return rc;
}

int
dacpo_pcd_write(const char* path,
                const float* xyz,
                const float* normals,
                size_t n,
                const char* comment,
                char* err,
                size_t errlen)
{
  if (!path || (n && !xyz)) {
    dacpo_support_err(err, errlen, "NULL argument");
    return DACPO_PLY_ERR_ARGUMENT;
  }
  FILE* fp = fopen(path, "wb");
  if (!fp) {
    dacpo_support_err(
        err, errlen, "cannot open '%s' for writing: %s", path, strerror(errno));
    return DACPO_PLY_ERR_IO;
  }
  fprintf(fp, "# .PCD v0.7 - Point Cloud Data file format\n");
  for (const char* c = comment; c && *c;) { /* one # line per comment line */
    const char* nl = strchr(c, '\n');
    const int len = (int)(nl ? (size_t)(nl - c) : strlen(c));
    fprintf(fp, "# %.*s\n", len, c);
    c += len + (nl != NULL);
  }
  const int nv = normals ? 6 : 3;
  fprintf(fp,
          "VERSION 0.7\nFIELDS x y z%s\nSIZE%s\nTYPE%s\nCOUNT%s\n",
          normals ? " normal_x normal_y normal_z" : "",
          normals ? " 4 4 4 4 4 4" : " 4 4 4",
          normals ? " F F F F F F" : " F F F",
          normals ? " 1 1 1 1 1 1" : " 1 1 1");
  fprintf(fp,
          "WIDTH %zu\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS %zu\nDATA binary\n",
          n,
          n);
  int ok = 1;
  for (size_t i = 0; i < n && ok; ++i) {
    unsigned char rec[24]; /* little-endian, whatever the host's order */
    for (int k = 0; k < nv; ++k) {
      uint32_t w;
      memcpy(&w, k < 3 ? xyz + 3 * i + k : normals + 3 * i + (k - 3), 4);
      for (int b = 0; b < 4; ++b)
        rec[4 * k + b] = (unsigned char)(w >> (8 * b));
    }
    ok = fwrite(rec, 4, (size_t)nv, fp) == (size_t)nv;
  }
  if (fclose(fp) != 0)
    ok = 0;
  if (!ok) {
    dacpo_support_err(err, errlen, "write error on '%s': %s", path, strerror(errno));
    return DACPO_PLY_ERR_IO;
  }
  return DACPO_PLY_OK;
}

int
dacpo_points_read(const char* path, dacpo_ply_cloud* out, char* err, size_t errlen)
{
  return dacpo_is_pcd_path(path) ? dacpo_pcd_read(path, out, err, errlen)
                                 : dacpo_ply_read(path, out, err, errlen);
}

int
dacpo_points_write(const char* path,
                   const float* xyz,
                   const float* normals,
                   size_t n,
                   const char* comment,
                   char* err,
                   size_t errlen)
{
  return dacpo_is_pcd_path(path)
             ? dacpo_pcd_write(path, xyz, normals, n, comment, err, errlen)
             : dacpo_ply_write(path, xyz, normals, n, comment, err, errlen);
}
