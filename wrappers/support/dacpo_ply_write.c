/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * PLY writer (dacpo_ply.h): dacpo_ply_write and dacpo_ply_write_exact.
 *
 * Writer: binary little-endian, float x y z [nx ny nz], byte order fixed by
 * explicit shifts so the output is the same on any host.
 */
#define _FILE_OFFSET_BITS 64
#define _POSIX_C_SOURCE 200809L
#include "dacpo_ply.h"

#include "dacpo_support_err.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------- */
/* Writer.                                                                    */

static unsigned char*
put_f32le(unsigned char* p, float f)
{
  uint32_t u;
  memcpy(&u, &f, sizeof(u));
  p[0] = (unsigned char)(u & 0xffu);
  p[1] = (unsigned char)((u >> 8) & 0xffu);
  p[2] = (unsigned char)((u >> 16) & 0xffu);
  p[3] = (unsigned char)((u >> 24) & 0xffu);
  return p + 4;
}

static unsigned char*
put_f64le(unsigned char* p, double d)
{
  uint64_t u;
  memcpy(&u, &d, sizeof(u));
  for (int b = 0; b < 8; ++b)
    p[b] = (unsigned char)((u >> (8 * b)) & 0xffu);
  return p + 8;
}

/* Each line of `comment` becomes one "comment" header line. */
static int
write_comments(FILE* f, const char* comment)
{
  const char* p = comment;
  if (!comment)
    return 0;
  while (*p) {
    const char* e = strchr(p, '\n');
    const size_t len = e ? (size_t)(e - p) : strlen(p);
    if (fprintf(f, "comment %.*s\n", (int)(len > 4000 ? 4000 : len), p) < 0)
      return -1;
    p += len;
    if (*p == '\n')
      ++p;
  }
  return 0;
}

/* Float (xyz) or double (xyz_d) coordinates, float normals when given. */
static int
ply_write(const char* path,
          const float* xyz,
          const double* xyz_d,
          const float* normals,
          size_t n,
          const char* comment,
          char* err,
          size_t errlen)
{
  const size_t per = 3 * (xyz_d ? 2 : 1) + (normals ? 3 : 0);
  const char* type = xyz_d ? "double" : "float";
  const size_t chunk = 4096;
  unsigned char* buf;
  FILE* f;
  int bad = 0;

  if (err && errlen > 0)
    err[0] = '\0';
  if (!path || (!xyz && !xyz_d && n > 0)) {
    dacpo_support_err(
        err, errlen, "dacpo_ply_write: %s is NULL", !path ? "path" : "xyz");
    return DACPO_PLY_ERR_ARGUMENT;
  }
  buf = (unsigned char*)malloc(chunk * per * 4); /* per counts 4-byte words */
  if (!buf) {
    dacpo_support_err(err, errlen, "out of memory");
    return DACPO_PLY_ERR_MEMORY;
  }
  f = fopen(path, "wb");
  if (!f) {
    dacpo_support_err(
        err, errlen, "cannot open '%s' for writing: %s", path, strerror(errno));
    free(buf);
    return DACPO_PLY_ERR_IO;
  }
  if (fprintf(f, "ply\nformat binary_little_endian 1.0\n") < 0 ||
      write_comments(f, comment) != 0 ||
      fprintf(f,
              "element vertex %zu\nproperty %s x\nproperty %s y\nproperty %s z\n",
              n,
              type,
              type,
              type) < 0 ||
      (normals && fprintf(f,
                          "property float nx\nproperty float ny\n"
                          "property float nz\n") < 0) ||
      fprintf(f, "end_header\n") < 0)
    bad = 1;
  for (size_t i0 = 0; i0 < n && !bad; i0 += chunk) {
    const size_t m = n - i0 < chunk ? n - i0 : chunk;
    unsigned char* p = buf;
    for (size_t i = i0; i < i0 + m; ++i) {
      for (size_t k = 0; k < 3; ++k)
        p = xyz_d ? put_f64le(p, xyz_d[3 * i + k]) : put_f32le(p, xyz[3 * i + k]);
      if (normals)
        for (size_t k = 0; k < 3; ++k)
          p = put_f32le(p, normals[3 * i + k]);
    }
    if (fwrite(buf, 1, (size_t)(p - buf), f) != (size_t)(p - buf))
      bad = 1;
  }
  free(buf);
  if (bad) {
    dacpo_support_err(err, errlen, "write error on '%s': %s", path, strerror(errno));
    fclose(f);
    return DACPO_PLY_ERR_IO;
  }
  if (fclose(f) != 0) {
    dacpo_support_err(
        err, errlen, "write error on '%s' (close): %s", path, strerror(errno));
    return DACPO_PLY_ERR_IO;
  }
  return DACPO_PLY_OK;
}

int
dacpo_ply_write(const char* path,
                const float* xyz,
                const float* normals,
                size_t n,
                const char* comment,
                char* err,
                size_t errlen)
{
  return ply_write(path, xyz, NULL, normals, n, comment, err, errlen);
}

int
dacpo_ply_write_exact(const char* path,
                      const double* xyz,
                      const float* normals,
                      size_t n,
                      const char* comment,
                      char* err,
                      size_t errlen)
{
  return ply_write(path, NULL, xyz, normals, n, comment, err, errlen);
}
