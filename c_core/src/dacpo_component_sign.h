/* SPDX-License-Identifier: BSD-3-Clause */
/* Relative sign of disconnected parts from a viewpoint inferred from the
 * largest part (policy DACPO_DISCONNECTED_VIEWPOINT). */
#ifndef DACPO_COMPONENT_SIGN_H
#define DACPO_COMPONENT_SIGN_H

#include "dacpo_internal.h"

/* xyz, nrm: n points and their oriented normals (3n each); component[i] in
 * [0, num_components). Writes, per component, sign[c] in {+1, -1} (multiply
 * the component's normals by it) and confidence[c] in [0, 1] (the vote margin
 * |facing - not facing| / size; 1 for the largest component, 0 when no
 * viewpoint explains the largest one, then every sign stays +1). *score_out
 * (may be NULL) gets the fraction of the largest component facing the inferred
 * viewpoint. Failures: NULL argument (INVALID_ARGUMENT), OUT_OF_MEMORY. */
dacpo_status
dacpo_component_signs(const double* xyz,
                      const double* nrm,
                      size_t n,
                      const int32_t* component,
                      size_t num_components,
                      uint64_t seed,
                      int8_t* sign,
                      double* confidence,
                      double* score_out,
                      dacpo_err* err);

#endif
