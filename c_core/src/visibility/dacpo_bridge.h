/* SPDX-License-Identifier: BSD-3-Clause */
/* Optional policy for a disconnected k-NN graph: join the components with
 * bridge edges so the whole cloud is oriented as one (never silent: the
 * caller reports the counts). */
#ifndef DACPO_BRIDGE_H
#define DACPO_BRIDGE_H

#include "dacpo_knn.h"

/* Largest `extra` accepted (further cross pairs per tree edge). */
enum { DACPO_BRIDGE_MAX_EXTRA = 64 };

/* Adds bridge edges so the adjacency becomes connected: a minimum spanning tree
 * over the components, where the distance between two components is the
 * shortest distance between their points (the Euclidean MST restricted to
 * inter-component pairs, built Boruvka-style). Each tree edge is realised by its
 * closest point pair (a, b) plus up to `extra` further cross pairs near it: the
 * nearest pairs between points a few adjacency hops from a and from b, distinct
 * endpoints first. Ties are broken by point index, so the result is unique.
 *
 * cloud, adj:     the distinct points and their symmetric adjacency (adj->n ==
 *                 cloud->n); component[i] in [0, num_components) as from
 *                 dacpo_components_label.
 * component:      in/out; set to all 0 on success (one component).
 * extra:          0..DACPO_BRIDGE_MAX_EXTRA.
 * out:            new adjacency (symmetric CSR, sorted rows, no self, no
 *                 repeats, same conventions as dacpo_adjacency_build); free with
 *                 dacpo_adjacency_free. With num_components <= 1 it is a copy
 *                 of adj. Zeroed on failure.
 * bridges_added:  undirected edges added (tree edges + extra pairs).
 * longest_bridge: length of the longest added edge (0 when none).
 *
 * Failures: NULL argument, size mismatch, label out of range, extra too large
 * (INVALID_ARGUMENT), allocation (OUT_OF_MEMORY). component[] is left untouched
 * on failure. Cost: O(n log n) build plus O(log C) rounds of one pruned search
 * per kd-tree leaf (later rounds skip leaves whose cached lower bound cannot
 * win); memory about 60 bytes per point. Single-threaded, no global state. */
dacpo_status
dacpo_bridge_components(const dacpo_cloud* cloud,
                        const dacpo_adjacency* adj,
                        int32_t* component,
                        size_t num_components,
                        size_t extra,
                        dacpo_adjacency* out,
                        size_t* bridges_added,
                        double* longest_bridge,
                        dacpo_err* err);

#endif
