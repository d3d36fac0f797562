/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 3a': iso-surface extraction (marching cubes) from the cell-centre
 * values of a dacpo_grid, as an indexed, consistently wound triangle mesh. */
#ifndef DACPO_MCUBES_H
#define DACPO_MCUBES_H

#include "dacpo_internal.h"
#include "dacpo_poisson.h"

/* Reusable extractor: keeps the mesh buffers and slab scratch between calls,
 * so iPSR does not reallocate every iteration. One per thread. */
typedef struct dacpo_mcubes dacpo_mcubes;

dacpo_status
dacpo_mcubes_create(dacpo_mcubes** out, dacpo_err* err);

void
dacpo_mcubes_free(dacpo_mcubes* mc);

/* Extracts {values == iso} over the cubes spanned by adjacent cell centres
 * (only cubes whose 8 cells are all in the domain: domain[i] != 0; a NULL
 * domain is the whole grid).
 * Vertices lie on grid edges (one per crossed edge, shared by all triangles
 * using it, plus a centroid vertex for the rare loop that crosses an ambiguous
 * face twice): the mesh is indexed, consistently oriented and watertight
 * inside the grid; its only boundary is on the outermost layer of cell centres.
 * Ambiguous cube faces are resolved by the asymptotic decider, consistently for both
 * cubes. Winding: the face normal (v1-v0)x(v2-v0) points towards values > iso (for a
 * dacpo_poisson chi: along the sample normals).
 * *mesh points into mc and stays valid until the next extract or free.
 * Errors: INVALID_ARGUMENT, OUT_OF_MEMORY. */
dacpo_status
dacpo_mcubes_extract(dacpo_mcubes* mc,
                     const dacpo_grid* grid,
                     const float* values,
                     const uint8_t* domain,
                     double iso,
                     const dacpo_mesh** mesh,
                     dacpo_err* err);

/* Bytes currently allocated by the extractor (mesh included). */
size_t
dacpo_mcubes_bytes(const dacpo_mcubes* mc);

#endif /* DACPO_MCUBES_H */
