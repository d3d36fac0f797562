/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * The block and edge units of dacpo_advanced.h one at a time: in this process
 * (dacpo_job_orient_block, dacpo_job_weigh_edge) or as bytes for another
 * (dacpo_job_block_task -> dacpo_block_task_run -> dacpo_job_put_block, the
 * same for edges; the byte format is in dacpo_block_unit.c). Each checks that
 * its unit may run now (a valid id, not done yet, an edge's blocks done) and
 * reports into the caller's buffer: units may run on several threads at once.
 */
#include "dacpo_job_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- units for another process (dacpo_advanced.h) ------------------------ */

/* Whether block b may take a result: a valid id, not yet oriented. */
static dacpo_status
block_open(const dacpo_job* job, size_t b, dacpo_err* err)
{
  DACPO_CHECK(err,
              job && b < job->s.blocks.num_blocks,
              DACPO_ERR_INVALID_ARGUMENT,
              "job: block %zu of %zu",
              b,
              dacpo_job_num_blocks(job));
  DACPO_CHECK(err,
              !job->s.block_done[b],
              DACPO_ERR_INVALID_ARGUMENT,
              "job: block %zu is oriented already",
              b);
  return DACPO_OK;
}

static dacpo_status
job_block_task(
    const dacpo_job* job, size_t b, void** bytes, size_t* size, dacpo_err* err)
{
  DACPO_CHECK(err,
              job && b < job->s.blocks.num_blocks,
              DACPO_ERR_INVALID_ARGUMENT,
              "job: block %zu of %zu",
              b,
              dacpo_job_num_blocks(job));
  const run_state* s = &job->s;
  const size_t n = dacpo_run_block_size(s, b);
  if (!bytes) /* size only */
    return dacpo_block_task_pack(&s->p,
                                 b,
                                 NULL,
                                 NULL,
                                 n,
                                 dacpo_run_block_own(s, b),
                                 s->meshes != NULL,
                                 NULL,
                                 size,
                                 err);
  double* xyz = dacpo_malloc_array(3 * n, sizeof(double));
  double* axes = dacpo_malloc_array(3 * n, sizeof(double));
  dacpo_status st = xyz && axes ? DACPO_OK : DACPO_OOM(err);
  if (st == DACPO_OK) {
    dacpo_run_gather_block(s, b, xyz, axes);
    st = dacpo_block_task_pack(&s->p,
                               b,
                               xyz,
                               axes,
                               n,
                               dacpo_run_block_own(s, b),
                               s->meshes != NULL,
                               bytes,
                               size,
                               err);
  }
  free(xyz);
  free(axes);
  return st;
}

dacpo_status
dacpo_job_block_task(const dacpo_job* job,
                     size_t b,
                     void** bytes,
                     size_t* size,
                     char* msg,
                     size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  if (!size)
    dacpo_err_set(&err, DACPO_ERR_INVALID_ARGUMENT, "job: size is NULL");
  else {
    if (bytes)
      *bytes = NULL;
    *size = 0;
    job_block_task(job, b, bytes, size, &err);
  }
  return dacpo_unit_message(&err, msg, msg_size);
}

static dacpo_status
job_put_block(dacpo_job* job, const void* bytes, size_t size, dacpo_err* err)
{
  DACPO_CHECK(err, job != NULL, DACPO_ERR_INVALID_ARGUMENT, "job: job is NULL");
  dacpo_block_out out;
  size_t b, n, no;
  int has_mesh;
  DACPO_TRY(dacpo_block_result_unpack(bytes, size, &b, &n, &no, &has_mesh, &out, err));
  dacpo_status st = block_open(job, b, err);
  if (st == DACPO_OK &&
      (n != dacpo_run_block_size(&job->s, b) || no != dacpo_run_block_own(&job->s, b) ||
       has_mesh != (job->s.meshes != NULL)))
    st = dacpo_err_set(err,
                       DACPO_ERR_INVALID_ARGUMENT,
                       "job: the result for block %zu holds %zu points (%zu own, mesh "
                       "%d), the block %zu (%zu own, mesh %d)",
                       b,
                       n,
                       no,
                       has_mesh,
                       dacpo_run_block_size(&job->s, b),
                       dacpo_run_block_own(&job->s, b),
                       job->s.meshes != NULL);
  if (st == DACPO_OK)
    dacpo_run_store_block(&job->s, b, &out);
  dacpo_block_out_free(&out);
  return st;
}

dacpo_status
dacpo_job_put_block(
    dacpo_job* job, const void* bytes, size_t size, char* msg, size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  job_put_block(job, bytes, size, &err);
  return dacpo_unit_message(&err, msg, msg_size);
}

/* Whether edge e can be weighed by VCR now: a valid id, VCR weights, both
 * blocks oriented. */
static dacpo_status
edge_ready(const dacpo_job* job, size_t e, dacpo_err* err)
{
  DACPO_CHECK(err,
              job && e < job->s.bgraph.num_edges,
              DACPO_ERR_INVALID_ARGUMENT,
              "job: edge %zu of %zu",
              e,
              dacpo_job_num_edges(job));
  DACPO_CHECK(err,
              job->s.p.edge_weight == DACPO_WEIGHT_VCR,
              DACPO_ERR_INVALID_ARGUMENT,
              "job: edge by edge only with VCR weights; use dacpo_job_weigh_edges");
  const dacpo_block_edge* edge = &job->s.bgraph.edges[e];
  DACPO_CHECK(err,
              job->s.block_done[edge->a] && job->s.block_done[edge->b],
              DACPO_ERR_INVALID_ARGUMENT,
              "job: edge %zu before its blocks %d and %d are oriented",
              e,
              (int)edge->a,
              (int)edge->b);
  return DACPO_OK;
}

dacpo_status
dacpo_job_edge_task(const dacpo_job* job,
                    size_t e,
                    void** bytes,
                    size_t* size,
                    char* msg,
                    size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  if (!size)
    dacpo_err_set(&err, DACPO_ERR_INVALID_ARGUMENT, "job: size is NULL");
  else {
    if (bytes)
      *bytes = NULL;
    *size = 0;
    if (edge_ready(job, e, &err) == DACPO_OK) {
      const dacpo_block_edge* edge = &job->s.bgraph.edges[e];
      dacpo_edge_task_pack(&job->s.p,
                           e,
                           &job->s.meshes[edge->a],
                           &job->s.meshes[edge->b],
                           bytes,
                           size,
                           &err);
    }
  }
  return dacpo_unit_message(&err, msg, msg_size);
}

dacpo_status
dacpo_job_put_edge(dacpo_job* job,
                   size_t e,
                   double alpha,
                   double alpha_bar,
                   char* msg,
                   size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  if (edge_ready(job, e, &err) == DACPO_OK) {
    if (job->s.edge_done[e])
      dacpo_err_set(
          &err, DACPO_ERR_INVALID_ARGUMENT, "job: edge %zu is weighed already", e);
    else if (!(alpha >= 0.0 && alpha_bar >= 0.0 && isfinite(alpha) &&
               isfinite(alpha_bar)))
      dacpo_err_set(&err,
                    DACPO_ERR_INVALID_ARGUMENT,
                    "job: edge %zu: alpha %g and alpha_bar %g must be finite and >= 0",
                    e,
                    alpha,
                    alpha_bar);
    else {
      job->s.bgraph.edges[e].alpha = alpha;
      job->s.bgraph.edges[e].alpha_bar = alpha_bar;
      job->s.edge_done[e] = 1;
    }
  }
  return dacpo_unit_message(&err, msg, msg_size);
}

dacpo_status
dacpo_job_orient_block(dacpo_job* job, size_t b, char* msg, size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  if (block_open(job, b, &err) == DACPO_OK)
    dacpo_run_orient_block(&job->s, b, 0, &err);
  return dacpo_unit_message(&err, msg, msg_size);
}

dacpo_status
dacpo_job_weigh_edge(dacpo_job* job, size_t e, char* msg, size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  if (edge_ready(job, e, &err) == DACPO_OK)
    dacpo_run_weigh_edge_vcr(&job->s, e, 0, &err);
  return dacpo_unit_message(&err, msg, msg_size);
}
