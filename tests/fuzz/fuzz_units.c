/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * libFuzzer target: the messages of the work units that cross processes
 * (dacpo_advanced.h): the input bytes as a block task, an edge task and a
 * block result for a small job.
 *
 * Byte 0 picks the message kind a valid prefix is built for (0: raw bytes,
 * 1: a block task of the job, 2: a block result, 3: an edge task); the rest
 * overwrites that message from byte 1 on (so headers, counts and arrays all
 * get mutated around a valid message). The job is made once, from a
 * generated-looking cloud of 400 points on two planes.
 *
 * Contract checked: no crash, no sanitizer report, no hang on any message; a
 * refused message leaves a message; an accepted result leaves the block
 * oriented, after which the same block is refused.
 */
#include <dacpo/dacpo.h>
#include <dacpo/dacpo_advanced.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define NPTS 400

static dacpo_ctx* ctx;
static void* valid[4];
static size_t valid_size[4];

static void
make_job(dacpo_job** job)
{
  static float xyz[3 * NPTS];
  for (int i = 0; i < NPTS; ++i) { /* a floor and a wall meeting at x = 0 */
    const float u = (float)(i % 20) * 0.05f, v = (float)(i / 20 % 10) * 0.05f;
    if (i < NPTS / 2) {
      xyz[3 * i] = u;
      xyz[3 * i + 1] = v;
      xyz[3 * i + 2] = 0.0f;
    }
    else {
      xyz[3 * i] = 0.0f;
      xyz[3 * i + 1] = v + 0.01f;
      xyz[3 * i + 2] = u + 0.05f;
    }
  }
  dacpo_params p;
  dacpo_params_init(&p);
  p.estimate_normals = 1;
  p.num_blocks = 3;
  p.num_threads = 1;
  if (dacpo_job_create(ctx, &p, NULL, NULL, xyz, NULL, NPTS, job) != DACPO_OK)
    abort();
}

/* A block task, the result of running it, and an edge task, once. */
static void
init(void)
{
  dacpo_ctx_create(&ctx);
  dacpo_job* job = NULL;
  make_job(&job);
  char msg[256];
  if (dacpo_job_block_task(job, 0, &valid[1], &valid_size[1], msg, sizeof(msg)) ||
      dacpo_block_task_run(
          valid[1], valid_size[1], &valid[2], &valid_size[2], msg, sizeof(msg)))
    abort();
  for (size_t b = 0; b < dacpo_job_num_blocks(job); ++b)
    if (dacpo_job_orient_block(job, b, msg, sizeof(msg)))
      abort();
  if (dacpo_job_num_edges(job) == 0 ||
      dacpo_job_edge_task(job, 0, &valid[3], &valid_size[3], msg, sizeof(msg)))
    abort();
  dacpo_job_free(job);
}

int
LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  if (!ctx)
    init();
  if (size < 1)
    return 0;
  const unsigned kind = data[0] % 4;
  size_t n = kind ? valid_size[kind] : size - 1;
  if (kind && size - 1 > n)
    n = size - 1; /* longer than the valid message: extra bytes */
  uint8_t* m = malloc(n + 1);
  if (!m)
    return 0;
  if (kind)
    memcpy(m, valid[kind], valid_size[kind] < n ? valid_size[kind] : n);
  memcpy(m, data + 1, size - 1 < n ? size - 1 : n);
  if (kind && size - 1 < valid_size[kind] && (data[0] & 4))
    n = size - 1; /* cut short */
  char msg[256];
  void* res = NULL;
  size_t res_size = 0;
  double a = 0.0, b = 0.0;
  if (dacpo_block_task_run(m, n, &res, &res_size, msg, sizeof(msg)) != DACPO_OK) {
    if (msg[0] == '\0' || res != NULL)
      abort();
  }
  dacpo_unit_bytes_free(res);
  if (dacpo_edge_task_run(m, n, &a, &b, msg, sizeof(msg)) != DACPO_OK) {
    if (msg[0] == '\0')
      abort();
  }
  else if (!(isfinite(a) && isfinite(b) && a >= 0.0 && b >= 0.0))
    abort();
  /* a fresh job for every result message (raw bytes or a mutated result):
   * it takes it once at most */
  if (kind != 0 && kind != 2) {
    free(m);
    return 0;
  }
  dacpo_job* job = NULL;
  make_job(&job);
  if (dacpo_job_put_block(job, m, n, msg, sizeof(msg)) == DACPO_OK) {
    size_t nb = dacpo_job_num_blocks(job);
    int refused = 0;
    for (size_t blk = 0; blk < nb; ++blk) /* the block it named is now taken */
      refused += dacpo_job_put_block(job, m, n, msg, sizeof(msg)) != DACPO_OK;
    if (refused != (int)nb)
      abort();
  }
  else if (msg[0] == '\0')
    abort();
  dacpo_job_free(job);
  free(m);
  return 0;
}
