/* SPDX-License-Identifier: BSD-3-Clause */
/* orient_minimal: the C API in one page. Builds a tiny open box corner (floor and
 * two walls, normals with random signs), orients it, prints status and stats. */
#include <dacpo/dacpo.h>

#include <stdio.h>
#include <stdlib.h>

#define SIDE 30 /* samples per edge of each square face */

int
main(void)
{
  const size_t n = 3 * SIDE * SIDE;
  float* xyz = malloc(3 * n * sizeof(float));
  float* normals = malloc(3 * n * sizeof(float));
  if (!xyz || !normals) {
    fprintf(stderr, "out of memory\n");
    return 1;
  }
  /* Face f has normal axis f (z floor, x wall, y wall); signs scrambled. */
  size_t i = 0;
  for (int f = 0; f < 3; ++f)
    for (int a = 0; a < SIDE; ++a)
      for (int b = 0; b < SIDE; ++b, ++i) {
        const float u = (a + 0.5f) / SIDE, v = (b + 0.5f) / SIDE;
        const float p[3][3] = {{u, v, 0.0f}, {0.0f, u, v}, {u, 0.0f, v}};
        const int axis[3] = {2, 0, 1};
        for (int d = 0; d < 3; ++d) {
          xyz[3 * i + d] = p[f][d];
          normals[3 * i + d] = 0.0f;
        }
        normals[3 * i + axis[f]] = (rand() & 1) ? 1.0f : -1.0f;
      }

  dacpo_ctx* ctx = NULL;
  if (dacpo_ctx_create(&ctx) != DACPO_OK) {
    fprintf(stderr, "cannot create a context\n");
    return 1;
  }
  dacpo_params params;
  dacpo_params_init(&params); /* defaults: k = 10, given normals used as axes */
  const dacpo_status status = dacpo_orient(ctx, &params, NULL, NULL, xyz, normals, n);
  printf("dacpo %s: %s", dacpo_version_string(), dacpo_status_string(status));
  if (status != DACPO_OK)
    printf(" (%s)", dacpo_ctx_last_error(ctx));
  printf("\n");

  if (status == DACPO_OK) {
    const dacpo_stats* s = dacpo_ctx_stats(ctx);
    printf("%zu points, %zu blocks, %zu block edges, %zu flipped, %zu component(s), "
           "solver %s, %.3f s\n",
           s->input_points,
           s->num_blocks,
           s->num_block_edges,
           s->flipped_blocks,
           s->num_components,
           s->solver_optimal ? "optimal" : "not proven optimal",
           s->total_seconds);
    /* All inner faces should now point the same way relative to the room:
     * count the normals of each face that agree with its first one. */
    for (int f = 0; f < 3; ++f) {
      size_t agree = 0;
      const size_t first = (size_t)f * SIDE * SIDE;
      for (size_t j = first; j < first + SIDE * SIDE; ++j)
        agree += normals[3 * j] * normals[3 * first] +
                     normals[3 * j + 1] * normals[3 * first + 1] +
                     normals[3 * j + 2] * normals[3 * first + 2] >
                 0.0f;
      printf("face %d: %zu of %d normals agree\n", f, agree, SIDE * SIDE);
    }
  }
  dacpo_ctx_free(ctx);
  free(xyz);
  free(normals);
  return status == DACPO_OK ? 0 : 1;
}
