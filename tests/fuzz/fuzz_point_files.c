/* SPDX-License-Identifier: BSD-3-Clause */
/* libFuzzer target: the plain-C point file readers of wrappers/support
 * (dacpo_points_read: dacpo_pcd.c for .pcd, dacpo_ply.c for .ply, chosen by the
 * first byte's low bit) on arbitrary bytes, and for .ply also the range reader
 * of the tiles (dacpo_ply_rows_open / _read). Contract: no crash or sanitizer
 * report; a failure comes with a message and an empty cloud; a success has
 * positions for every point it counts, and the range reader agrees with it. */
#include "dacpo_pcd.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int
LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  if (size < 1)
    return 0;
  char path[64];
  snprintf(path,
           sizeof(path),
           "/tmp/dacpo_fuzz_pts_%ld.%s",
           (long)getpid(),
           (data[0] & 1) ? "ply" : "pcd");
  FILE* f = fopen(path, "wb");
  if (!f)
    return 0;
  fwrite(data + 1, 1, size - 1, f);
  fclose(f);
  dacpo_ply_cloud c;
  char err[256] = "";
  const int rc = dacpo_points_read(path, &c, err, sizeof(err));
  dacpo_ply_rows rows;
  char err2[256] = "";
  const int rrc = (data[0] & 1) ? dacpo_ply_rows_open(path, &rows, err2, sizeof(err2)) : -1;
  if ((data[0] & 1) && rrc != DACPO_PLY_OK && err2[0] == '\0')
    abort();
  if (rrc == DACPO_PLY_OK) {
    /* a binary file the range reader accepts is one the whole reader read */
    if (rc != DACPO_PLY_OK || rows.n != c.n)
      abort();
    FILE* g = fopen(path, "rb");
    float xyz[3 * 16];
    const size_t take = rows.n < 16 ? (size_t)rows.n : 16;
    if (g && dacpo_ply_rows_read(g, &rows, rows.n - take, take, xyz, err2, sizeof(err2)) ==
                 DACPO_PLY_OK)
      for (size_t i = 0; i < 3 * take; ++i)
        if (memcmp(&xyz[i], &c.xyz[3 * (rows.n - take) + i], sizeof(float)) != 0 &&
            !(xyz[i] != xyz[i]))
          abort();
    if (g)
      fclose(g);
  }
  remove(path);
  if (rc != DACPO_PLY_OK && (err[0] == '\0' || c.n != 0 || c.xyz || c.normals))
    abort();
  if (rc == DACPO_PLY_OK && c.n > 0 && !c.xyz)
    abort();
  volatile float sink = 0.0f; /* every value is readable (ASan checks the bounds) */
  for (size_t i = 0; rc == DACPO_PLY_OK && i < 3 * c.n; ++i)
    sink += c.xyz[i] + (c.normals ? c.normals[i] : 0.0f);
  (void)sink;
  dacpo_ply_cloud_free(&c);
  return 0;
}
