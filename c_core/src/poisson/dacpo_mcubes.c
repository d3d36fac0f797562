/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 3a': marching cubes on cell-centred grid values (paper §4.3: iPSR
 * extracts the iso-surface of the screened Poisson indicator each iteration).
 *
 * Inputs: a dacpo_grid, its values, an optional domain mask (only cubes whose
 * 8 cells are in the domain are polygonised: the Poisson solver's narrow band),
 * an iso-value. Output: an indexed triangle mesh whose face normals point
 * towards values > iso.
 *
 * No case table is stored: each cube's polygons are built from its faces.
 * Walking each cube face counter-clockwise as seen from outside, a crossed
 * edge where the walk goes from a high corner to a low one ("leave") starts a
 * contour segment and one going low to high ("enter") ends one, so the high
 * side is always on the segment's left. Every crossed cube edge lies on two
 * faces, walked in opposite directions, so it leaves on one face and enters
 * on the other: the segments chain into closed loops, which are fanned into
 * triangles whose normals point to the high side. Faces with four crossings
 * pair them by the asymptotic decider (sign of the bilinear saddle value), a
 * function of the face's four values only, so both cubes sharing a face agree
 * and the surface is watertight. A loop that runs through both segments of one
 * such face is fanned around an extra centroid vertex, so no triangle edge can
 * lie inside a cube face (where the neighbour cube could repeat it).
 *
 * Vertices are made once per crossed grid edge and looked up by edge through
 * two slabs of edge ids (the mesh is indexed, nothing is deduplicated later).
 * A first pass codes every cell as outside / low / high in one byte and marks
 * rows without domain cells, so empty space costs a byte read per cell.
 * Cost: O(cells) with a tiny constant for empty cubes; memory one byte per
 * cell, O(nx*ny) slabs, and the mesh. Failure modes: OUT_OF_MEMORY.
 */
#include "dacpo_mcubes.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

struct dacpo_mcubes {
  dacpo_mesh mesh;
  size_t vcap;
  size_t tcap;
  int32_t* slab;   /* 5 * slab_cap: x/y edge ids of two cell layers, z edge ids */
  size_t slab_cap; /* entries per slab part */
  uint8_t* code;   /* code_cap cells (0 outside the domain, 1 low, 2 high), then rows */
  uint8_t* rowany; /* per row (j, k): any domain cell; inside code */
  size_t code_cap; /* bytes */
};

/* Corners: bit 0 = +x, bit 1 = +y, bit 2 = +z. Faces: corners counter-clockwise
 * seen from outside the cube. */
static const int kFace[6][4] = {
    {0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

/* Edge index of the cube edge joining corners a and b (differ in one bit):
 * 4 * axis + the other two bits of the lower corner. */
static int
edge_of(int a, int b)
{
  int lo = a < b ? a : b;
  int bit = a ^ b;
  int axis = bit == 1 ? 0 : (bit == 2 ? 1 : 2);
  int rest;
  if (axis == 0)
    rest = (lo >> 1) & 3;
  else if (axis == 1)
    rest = (lo & 1) | ((lo >> 1) & 2);
  else
    rest = lo & 3;
  return 4 * axis + rest;
}

dacpo_status
dacpo_mcubes_create(dacpo_mcubes** out, dacpo_err* err)
{
  DACPO_CHECK(err, out, DACPO_ERR_INVALID_ARGUMENT, "mcubes: out is NULL");
  *out = (dacpo_mcubes*)calloc(1, sizeof(dacpo_mcubes));
  if (!*out)
    return DACPO_OOM(err);
  return DACPO_OK;
}

void
dacpo_mcubes_free(dacpo_mcubes* mc)
{
  if (!mc)
    return;
  free(mc->mesh.vertices);
  free(mc->mesh.triangles);
  free(mc->slab);
  free(mc->code);
  free(mc);
}

size_t
dacpo_mcubes_bytes(const dacpo_mcubes* mc)
{
  if (!mc)
    return 0;
  return sizeof(*mc) + mc->vcap * 3 * sizeof(double) + mc->tcap * 3 * sizeof(int32_t) +
         mc->slab_cap * 5 * sizeof(int32_t) + mc->code_cap;
}

static int
grow_vertices(dacpo_mcubes* mc)
{
  size_t cap = mc->vcap ? 2 * mc->vcap : 4096;
  if (cap > (size_t)INT32_MAX || cap > SIZE_MAX / (3 * sizeof(double)))
    return 0;
  double* v = (double*)realloc(mc->mesh.vertices, cap * 3 * sizeof(double));
  if (!v)
    return 0;
  mc->mesh.vertices = v;
  mc->vcap = cap;
  return 1;
}

static int
grow_triangles(dacpo_mcubes* mc)
{
  size_t cap = mc->tcap ? 2 * mc->tcap : 8192;
  if (cap > SIZE_MAX / (3 * sizeof(int32_t)))
    return 0;
  int32_t* t = (int32_t*)realloc(mc->mesh.triangles, cap * 3 * sizeof(int32_t));
  if (!t)
    return 0;
  mc->mesh.triangles = t;
  mc->tcap = cap;
  return 1;
}

static int
emit(dacpo_mcubes* mc, int32_t a, int32_t b, int32_t c)
{
  if (mc->mesh.num_triangles == mc->tcap && !grow_triangles(mc))
    return 0;
  int32_t* tri = mc->mesh.triangles + 3 * mc->mesh.num_triangles++;
  tri[0] = a;
  tri[1] = b;
  tri[2] = c;
  return 1;
}

/* Adds the vertex on the crossed grid edge from cell idx along axis. */
static int32_t
edge_vertex(dacpo_mcubes* mc,
            const dacpo_grid* g,
            const float* val,
            size_t idx,
            size_t stride,
            int axis,
            float iso)
{
  if (mc->mesh.num_vertices == mc->vcap && !grow_vertices(mc))
    return -2;
  const float va = val[idx], vb = val[idx + stride];
  float t = (iso - va) / (vb - va);
  if (!(t >= 0.0f))
    t = 0.0f;
  if (t > 1.0f)
    t = 1.0f;
  const size_t nx = g->dims[0], ny = g->dims[1];
  const size_t node[3] = {idx % nx, (idx / nx) % ny, idx / (nx * ny)};
  double* p = mc->mesh.vertices + 3 * mc->mesh.num_vertices;
  for (int a = 0; a < 3; ++a)
    p[a] = g->origin[a] +
           ((double)node[a] + 0.5 + (a == axis ? (double)t : 0.0)) * g->cell;
  return (int32_t)mc->mesh.num_vertices++;
}

/* Vertex ids of the crossed edges leaving the cells of row (j, k) along
 * `axis` (ids[i] = -1 where not crossed). code: 0 outside, 1 low, 2 high. */
static int
row_edges(dacpo_mcubes* mc,
          const dacpo_grid* g,
          const float* val,
          size_t j,
          size_t k,
          int axis,
          float iso,
          int32_t* ids)
{
  const size_t nx = g->dims[0], ny = g->dims[1], nz = g->dims[2];
  const size_t base = nx * (j + ny * k);
  const size_t stride = axis == 0 ? 1 : (axis == 1 ? nx : nx * ny);
  const uint8_t* code = mc->code + base;
  const int last = (axis == 1 && j + 1 >= ny) || (axis == 2 && k + 1 >= nz);
  if (last || !mc->rowany[j + ny * k] || (axis == 1 && !mc->rowany[j + 1 + ny * k]) ||
      (axis == 2 && !mc->rowany[j + ny * (k + 1)])) {
    memset(ids, 0xff, nx * sizeof(int32_t));
    return 1;
  }
  for (size_t i = 0; i < nx; ++i) {
    ids[i] = -1;
    const uint8_t ca = code[i];
    if (!ca || (axis == 0 && i + 1 >= nx))
      continue;
    const uint8_t cb = code[i + stride];
    if (cb && cb != ca) {
      ids[i] = edge_vertex(mc, g, val, base + i, stride, axis, iso);
      if (ids[i] == -2)
        return 0;
    }
  }
  return 1;
}

/* Buffers for a grid of nx x ny x nz values, then each cell's side of the
 * iso-value (code: 0 = outside the domain, 1 below, 2 above) and which rows
 * hold any domain cell. Returns 0 when out of memory. */
static int
mc_prepare(dacpo_mcubes* mc,
           size_t nx,
           size_t ny,
           size_t nz,
           const float* val,
           const uint8_t* dom,
           float iso)
{
  const size_t nxy = nx * ny;
  const size_t cells = nxy * nz;
  if (mc->slab_cap < nxy) {
    int32_t* s = (int32_t*)dacpo_malloc_array(5 * nxy, sizeof(int32_t));
    if (!s)
      return 0;
    free(mc->slab);
    mc->slab = s;
    mc->slab_cap = nxy;
  }
  if (mc->code_cap < cells + ny * nz) {
    uint8_t* c = (uint8_t*)dacpo_malloc_array(cells + ny * nz, 1);
    if (!c)
      return 0;
    free(mc->code);
    mc->code = c;
    mc->code_cap = cells + ny * nz;
  }
  mc->rowany = mc->code + cells;
  /* One pass: each cell's side of the iso-value (0 = outside the domain),
   * and which rows hold any domain cell. */
  for (size_t r = 0; r < ny * nz; ++r) {
    uint8_t any = 0;
    const size_t base = r * nx;
    for (size_t i = 0; i < nx; ++i) {
      uint8_t c = (!dom || dom[base + i]) ? (uint8_t)(1 + (val[base + i] > iso)) : 0;
      mc->code[base + i] = c;
      any |= c;
    }
    mc->rowany[r] = any != 0;
  }
  return 1;
}

/* The iso-surface segments on the six faces of one cube (corner signs in
 * mask, values relative to iso in v): next[e] is the edge the segment that
 * enters at edge e leaves by (-1: none), segface[e] the face it lies on. */
static void
cube_segments(int mask, const float v[8], int next[12], int segface[12])
{
  for (int e = 0; e < 12; ++e)
    next[e] = -1;
  for (int f = 0; f < 6; ++f) {
    const int* q = kFace[f];
    int cross[4], leave[4], nc = 0;
    for (int t = 0; t < 4; ++t) {
      int a = q[t], b = q[(t + 1) & 3];
      int ha = (mask >> a) & 1, hb = (mask >> b) & 1;
      if (ha != hb) {
        cross[nc] = edge_of(a, b);
        leave[nc] = ha;
        ++nc;
      }
    }
    if (nc == 2) {
      int from = leave[0] ? cross[0] : cross[1];
      next[from] = leave[0] ? cross[1] : cross[0];
      segface[from] = f;
    }
    else if (nc == 4) {
      /* Asymptotic decider: the bilinear interpolant's saddle value
       * (ac - bd) / (a + c - b - d) (relative to iso) decides whether
       * the high corners are joined across the face. */
      double a = v[q[0]], b = v[q[1]], c = v[q[2]], d = v[q[3]];
      double den = a + c - b - d;
      int joined = den != 0.0 && (a * c - b * d) / den > 0.0;
      for (int t = 0; t < 4; ++t)
        if (leave[t]) {
          next[cross[t]] = joined ? cross[(t + 1) & 3] : cross[(t + 3) & 3];
          segface[cross[t]] = f;
        }
    }
  }
}

/* Triangulates the loops of one cube (vid: the mesh vertex on each of its 12
 * edges). Returns 0 when out of memory. */
static int
cube_triangles(dacpo_mcubes* mc,
               const int32_t vid[12],
               const int next[12],
               const int segface[12])
{
  int seen[12] = {0};
  for (int e0 = 0; e0 < 12; ++e0) {
    if (next[e0] < 0 || seen[e0])
      continue;
    int loop[12], m = 0, faces = 0, twice = 0;
    for (int e = e0; e >= 0 && !seen[e] && m < 12; e = next[e]) {
      seen[e] = 1;
      loop[m++] = e;
      twice |= faces & (1 << segface[e]);
      faces |= 1 << segface[e];
    }
    if (!twice) {
      /* A fan: its chords join vertices on no common cube face, so they
       * run inside this cube and no neighbour can repeat them. */
      for (int t = 1; t + 1 < m; ++t)
        if (!emit(mc, vid[loop[0]], vid[loop[t]], vid[loop[t + 1]]))
          return 0;
      continue;
    }
    /* The loop crosses one face twice (both segments of an ambiguous
     * face): a fan chord could lie in that face, so fan around the
     * loop's centroid instead. */
    if (mc->mesh.num_vertices == mc->vcap && !grow_vertices(mc))
      return 0;
    double* cen = mc->mesh.vertices + 3 * mc->mesh.num_vertices;
    cen[0] = cen[1] = cen[2] = 0.0;
    for (int t = 0; t < m; ++t)
      for (int a = 0; a < 3; ++a)
        cen[a] += mc->mesh.vertices[3 * (size_t)vid[loop[t]] + a] / (double)m;
    int32_t ci = (int32_t)mc->mesh.num_vertices++;
    for (int t = 0; t < m; ++t)
      if (!emit(mc, ci, vid[loop[t]], vid[loop[(t + 1) % m]]))
        return 0;
  }
  return 1;
}

/* Cube (i, j, kc) of a layer: its corner mask (bit c set where corner c is
 * above iso) and its triangles, unless a corner is outside the domain or the
 * cube is not crossed. bx/by: the x/y edge vertex slabs of layers kc and
 * kc + 1, ez: the z edges between them. Returns 0 on allocation failure. */
static int
mc_cube(dacpo_mcubes* mc,
        const size_t* dims,
        const float* val,
        float iso,
        size_t i,
        size_t j,
        size_t kc,
        const int32_t* const bx[2],
        const int32_t* const by[2],
        const int32_t* ez)
{
  const size_t nx = dims[0], ny = dims[1], nxy = nx * ny;
  const uint8_t* c0 = mc->code + nx * (j + ny * kc);
  const uint8_t cc[8] = {c0[i],
                         c0[i + 1],
                         c0[i + nx],
                         c0[i + nx + 1],
                         c0[i + nxy],
                         c0[i + nxy + 1],
                         c0[i + nxy + nx],
                         c0[i + nxy + nx + 1]};
  int mask = 0, inside = 1;
  for (int c = 0; c < 8; ++c) {
    inside &= cc[c] != 0;
    mask |= (cc[c] >> 1) << c;
  }
  if (!inside || mask == 0 || mask == 255)
    return 1;
  float v[8];
  for (int c = 0; c < 8; ++c) {
    size_t idx =
        (i + (c & 1)) + nx * ((j + ((c >> 1) & 1)) + ny * (kc + ((c >> 2) & 1)));
    v[c] = val[idx] - iso;
  }
  int32_t vid[12];
  for (int e = 0; e < 4; ++e) {
    /* e's two bits are the lower corner's other two coordinates */
    const size_t lo = (size_t)(e & 1), hi = (size_t)(e >> 1);
    vid[e] = bx[hi][i + nx * (j + lo)];        /* x edges: (y, z) */
    vid[4 + e] = by[hi][(i + lo) + nx * j];    /* y edges: (x, z) */
    vid[8 + e] = ez[(i + lo) + nx * (j + hi)]; /* z edges: (x, y) */
  }
  int next[12], segface[12];
  cube_segments(mask, v, next, segface);
  return cube_triangles(mc, vid, next, segface);
}

dacpo_status
dacpo_mcubes_extract(dacpo_mcubes* mc,
                     const dacpo_grid* g,
                     const float* val,
                     const uint8_t* dom,
                     double iso_d,
                     const dacpo_mesh** mesh,
                     dacpo_err* err)
{
  DACPO_CHECK(
      err, mc && g && val && mesh, DACPO_ERR_INVALID_ARGUMENT, "mcubes: NULL argument");
  *mesh = &mc->mesh;
  mc->mesh.num_vertices = 0;
  mc->mesh.num_triangles = 0;
  const size_t nx = g->dims[0], ny = g->dims[1], nz = g->dims[2];
  if (nx < 2 || ny < 2 || nz < 2)
    return DACPO_OK;
  const size_t nxy = nx * ny;
  const float iso = (float)iso_d;
  if (!mc_prepare(mc, nx, ny, nz, val, dom, iso))
    return DACPO_OOM(err);
  int32_t* ex[2] = {mc->slab, mc->slab + nxy};
  int32_t* ey[2] = {mc->slab + 2 * nxy, mc->slab + 3 * nxy};
  int32_t* ez = mc->slab + 4 * nxy;

  for (size_t k = 0; k < nz; ++k) {
    /* x and y edges of cell layer k */
    for (size_t j = 0; j < ny; ++j)
      if (!row_edges(mc, g, val, j, k, 0, iso, ex[k & 1] + nx * j) ||
          !row_edges(mc, g, val, j, k, 1, iso, ey[k & 1] + nx * j))
        return DACPO_OOM(err);
    if (k == 0)
      continue;
    /* z edges between layers k-1 and k, then the cubes of that layer */
    const size_t kc = k - 1;
    for (size_t j = 0; j < ny; ++j)
      if (!row_edges(mc, g, val, j, kc, 2, iso, ez + nx * j))
        return DACPO_OOM(err);
    const int32_t* const bx[2] = {ex[kc & 1], ex[k & 1]};
    const int32_t* const by[2] = {ey[kc & 1], ey[k & 1]};
    for (size_t j = 0; j + 1 < ny; ++j) {
      const uint8_t* ra = mc->rowany;
      if (!ra[j + ny * kc] || !ra[j + 1 + ny * kc] || !ra[j + ny * k] ||
          !ra[j + 1 + ny * k])
        continue;
      for (size_t i = 0; i + 1 < nx; ++i)
        if (!mc_cube(mc, g->dims, val, iso, i, j, kc, bx, by, ez))
          return DACPO_OOM(err);
    }
  }
  return DACPO_OK;
}
