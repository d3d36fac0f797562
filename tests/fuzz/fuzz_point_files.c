/* SPDX-License-Identifier: BSD-3-Clause */
/* libFuzzer target: the plain-C point file readers of wrappers/support
 * (dacpo_points_read: dacpo_pcd.c for .pcd, dacpo_ply.c for .ply, chosen by the
 * first byte's low bit) on arbitrary bytes. Contract: no crash or sanitizer
 * report; a failure comes with a message and an empty cloud; a success has
 * positions for every point it counts. */
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
