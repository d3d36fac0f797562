/* SPDX-License-Identifier: BSD-3-Clause */
/* Stages 5-6 and the parts: the ordered sign passes (dacpo_sign_passes.c). */
#ifndef DACPO_SIGN_PASSES_H
#define DACPO_SIGN_PASSES_H

#include "dacpo_job_internal.h"

/* Runs the sign passes in their order on a run whose blocks are oriented and
 * whose edges are weighed: block flips, part signs, the global sign and the
 * surface vote's per-point turns, with their counts in st. */
dacpo_status
dacpo_sign_passes(run_state* s, dacpo_stats* st, dacpo_err* err);

/* The sign point i gets from the passes: its block's flip, its part's sign,
 * the global sign and its surface-vote turn. */
double
dacpo_sign_point(const run_state* s, size_t i);

#endif /* DACPO_SIGN_PASSES_H */
