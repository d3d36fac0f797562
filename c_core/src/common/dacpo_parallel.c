/* SPDX-License-Identifier: BSD-3-Clause */
/* Parallel for over independent tasks (blocks, edges) with POSIX threads.
 * Results never depend on the thread count: tasks write only their own slots
 * and derive randomness from their task index. */
#define _POSIX_C_SOURCE 200809L
#include "dacpo_parallel.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct pool {
  size_t num_tasks;
  dacpo_task_fn fn;
  void* user;
  atomic_size_t next;
  atomic_size_t done;
  atomic_int stop;
  pthread_mutex_t lock;
  size_t failed_task; /* lowest failing task index, SIZE_MAX if none */
  dacpo_err first_err;
} pool;

typedef struct worker {
  pool* p;
  unsigned id;
} worker;

/* Runs one task; returns 0 when no task was left or the pool is stopping. */
static int
run_one(pool* p, unsigned id)
{
  if (atomic_load(&p->stop))
    return 0;
  size_t t = atomic_fetch_add(&p->next, 1);
  if (t >= p->num_tasks)
    return 0;
  dacpo_err e = {DACPO_OK, {0}};
  dacpo_status s = p->fn(p->user, t, id, &e);
  if (s != DACPO_OK) {
    pthread_mutex_lock(&p->lock);
    if (t < p->failed_task) {
      p->failed_task = t;
      p->first_err = e;
      p->first_err.code = s;
      if (p->first_err.msg[0] == '\0')
        strncpy(p->first_err.msg, dacpo_status_string(s), sizeof(p->first_err.msg) - 1);
    }
    pthread_mutex_unlock(&p->lock);
    atomic_store(&p->stop, 1);
  }
  atomic_fetch_add(&p->done, 1);
  return 1;
}

static void*
worker_main(void* arg)
{
  worker* w = arg;
  while (run_one(w->p, w->id)) {
  }
  return NULL;
}

unsigned
dacpo_hardware_threads(void)
{
  long n = sysconf(_SC_NPROCESSORS_ONLN);
  return n > 0 ? (unsigned)n : 1u;
}

dacpo_status
dacpo_parallel_for(size_t num_tasks,
                   unsigned num_threads,
                   dacpo_task_fn fn,
                   void* user,
                   const dacpo_progress* progress,
                   dacpo_stage stage,
                   dacpo_err* err)
{
  if (num_tasks == 0)
    return DACPO_OK;
  unsigned nt = num_threads ? num_threads : dacpo_hardware_threads();
  if (nt > num_tasks)
    nt = (unsigned)num_tasks;
  pool p;
  p.num_tasks = num_tasks;
  p.fn = fn;
  p.user = user;
  atomic_init(&p.next, 0);
  atomic_init(&p.done, 0);
  atomic_init(&p.stop, 0);
  pthread_mutex_init(&p.lock, NULL);
  p.failed_task = SIZE_MAX;
  memset(&p.first_err, 0, sizeof(p.first_err));

  pthread_t* threads = NULL;
  worker* workers = NULL;
  unsigned started = 0;
  if (nt > 1) {
    threads = dacpo_malloc_array(nt, sizeof(pthread_t));
    workers = dacpo_malloc_array(nt, sizeof(worker));
    if (threads && workers) {
      for (unsigned i = 1; i < nt; ++i) {
        workers[i].p = &p;
        workers[i].id = i;
        if (pthread_create(&threads[i], NULL, worker_main, &workers[i]) != 0)
          break; /* fewer threads is still correct */
        started = i;
      }
    }
  }

  int cancelled = 0;
  while (run_one(&p, 0)) {
    if (progress && progress->fn && !cancelled) {
      double f = (double)atomic_load(&p.done) / (double)num_tasks;
      if (progress->fn(progress->user, stage, f) != 0) {
        cancelled = 1;
        atomic_store(&p.stop, 1);
      }
    }
  }
  for (unsigned i = 1; i <= started; ++i)
    pthread_join(threads[i], NULL);
  free(threads);
  free(workers);
  pthread_mutex_destroy(&p.lock);

  if (p.failed_task != SIZE_MAX) {
    if (err)
      *err = p.first_err;
    return p.first_err.code;
  }
  if (cancelled)
    return dacpo_err_set(err,
                         DACPO_ERR_CANCELLED,
                         "cancelled by the progress callback during %s",
                         dacpo_stage_name(stage));
  return DACPO_OK;
}
