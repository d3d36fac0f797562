/* SPDX-License-Identifier: BSD-3-Clause */
/* The paper's score (% of normals more than 90 degrees off the ground truth,
 * after one free sign per part) and sign scrambling for tests. Pure C. */
#ifndef DACPO_SCORE_H
#define DACPO_SCORE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/**
 * \brief Copy n normals and flip the sign of exactly round(fraction * n) of them,
 *        chosen uniformly at random (deterministic per seed).
 * \param[in]  normals_in   3n floats
 * \param[out] normals_out  3n floats; may equal normals_in (in place)
 * \param[in]  fraction     clamped to [0, 1]
 * \return the number of flipped normals.
 */
size_t
dacpo_scramble_signs(const float* normals_in,
                     float* normals_out,
                     size_t n,
                     uint64_t seed,
                     double fraction);

/**
 * \brief The paper's metric: percentage of points whose predicted normal makes
 *        more than 90 degrees with the ground truth, after one free sign.
 *
 * Without labels (component == NULL) the whole prediction may be flipped once,
 * so the result is at most 50 %. With labels, each label value (any int32) gets
 * its own free sign. A point whose dot product is zero or not finite counts as
 * wrong under either sign.
 * \param[out] wrong_out  number of wrong points (may be NULL)
 * \return the percentage in [0, 100]; 0 when n == 0; -1 when gt or pred is NULL
 *         (with n > 0) or out of memory.
 */
double
dacpo_score_oriented(const float* gt,
                     const float* pred,
                     size_t n,
                     const int32_t* component,
                     size_t* wrong_out);

#ifdef __cplusplus
}
#endif

#endif
