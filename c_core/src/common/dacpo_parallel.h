/* SPDX-License-Identifier: BSD-3-Clause */
/* A parallel for over independent tasks (blocks in stages 2-3, edges in stage 4).
 * Tasks are handed out by an atomic counter; results must not depend on which
 * thread ran a task. The calling thread works too and is the only one that calls
 * the progress callback. */
#ifndef DACPO_PARALLEL_H
#define DACPO_PARALLEL_H

#include "dacpo_internal.h"

/* One task. thread_id in [0, num_threads) lets a task use per-thread scratch. */
typedef dacpo_status (*dacpo_task_fn)(void* user,
                                      size_t task,
                                      unsigned thread_id,
                                      dacpo_err* err);

/* Runs fn(user, t, ...) for t in [0, num_tasks). Stops handing out tasks after
 * the first failure or a cancel from progress; returns the first error (lowest
 * task index among failures, so the message is deterministic) or
 * DACPO_ERR_CANCELLED. num_threads 0 = all cores. */
dacpo_status
dacpo_parallel_for(size_t num_tasks,
                   unsigned num_threads,
                   dacpo_task_fn fn,
                   void* user,
                   const dacpo_progress* progress,
                   dacpo_stage stage,
                   dacpo_err* err);

/* Number of online cores (at least 1). */
unsigned
dacpo_hardware_threads(void);

#endif
