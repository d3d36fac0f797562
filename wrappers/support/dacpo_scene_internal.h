/* SPDX-License-Identifier: BSD-3-Clause */
/* Private to wrappers/support (not included by dacpo_scene.h): the patch types
 * and the scene table shared by the generator (dacpo_scene.c) and the scene
 * definitions (dacpo_scene_shapes.c), and the helpers each takes from the other. */
#ifndef DACPO_SCENE_INTERNAL_H
#define DACPO_SCENE_INTERNAL_H

#include "dacpo_rng.h"
#include "dacpo_scene.h"

#include <stddef.h>
#include <stdint.h>

#define SCENE_PI 3.14159265358979323846
#define SCENE_MAX_HOLES 6
#define SCENE_MAX_PRIMS 192
#define SCENE_MAX_OBJECTS 32

/* Patches and the scene builder (dacpo_scene_shapes.c builds the patches). */
typedef enum prim_type {
  PRIM_QUAD,     /* p = c + s u + t v, s, t in [0, 1), minus holes; normal w */
  PRIM_CYLINDER, /* p = c + r (cos a e1 + sin a e2) + h' w; normal sign * radial */
  PRIM_ANNULUS,  /* p = c + rho (cos a e1 + sin a e2), rho in [r0, r1]; normal w */
  PRIM_SPHERE    /* p = c + r d; normal sign * d */
} prim_type;

typedef struct scene_prim {
  prim_type type;
  int32_t object;
  double c[3];
  double u[3], v[3]; /* quad: edge vectors; cylinder, annulus: unit frame e1, e2 */
  double w[3];       /* quad, annulus: unit normal; cylinder: unit axis */
  double r0, r1;     /* radius (cylinder, sphere); inner/outer radius (annulus) */
  double h;          /* cylinder height */
  double a0, a1;     /* cylinder angle range, radians */
  double sign;       /* cylinder, sphere: +1 outward normals, -1 inward */
  int nholes;
  double hole[SCENE_MAX_HOLES][4]; /* quad: s0, s1, t0, t1 in [0, 1] */
} scene_prim;

typedef struct scene_builder {
  scene_prim* prims; /* SCENE_MAX_PRIMS + 1; the last slot absorbs overflow */
  size_t count;
  const char* names[SCENE_MAX_OBJECTS];
  size_t num_objects;
  int overflow; /* a scene definition exceeded a fixed limit (programming error) */
} scene_builder;

typedef struct scene_entry {
  const char* name;
  void (*build)(scene_builder*);
} scene_entry;

/* Uniform unit vector (dacpo_scene.c, next to the Gaussian). */
void
dacpo_scene_rng_unit_vector(dacpo_rng* r, double d[3]);
/* The rotation by th radians about the unit axis a (Rodrigues), row-major. */
void
dacpo_scene_rotation(const double a[3], double th, double rot[9]);

/* Euclidean length of a 3-vector. */
double
dacpo_scene_norm3(const double a[3]);

/* Area of patch p, holes subtracted. */
double
dacpo_scene_prim_area(const scene_prim* p);

/* One uniform sample on patch p: position and unit normal, in double. */
void
dacpo_scene_prim_sample(const scene_prim* p,
                        dacpo_rng* r,
                        double pos[3],
                        double nrm[3]);

/* Depth-camera views (dacpo_scene_views.c): params->target_points points of
 * the patches of b, view by view and each row by row, into s (xyz, normals, part; s->n
 * set), cameras into info. Returns 0, or -1 with a message when no camera place is
 * found or a view sees too little. */
int
dacpo_scene_sample_views(const scene_builder* b,
                         const dacpo_scene_params* params,
                         dacpo_scene* s,
                         dacpo_scene_view_info* info,
                         char* err,
                         size_t errlen);

/* Name and builder of each scene kind, indexed by dacpo_scene_kind. */
extern const scene_entry dacpo_scene_table[DACPO_SCENE_KIND_COUNT];

#endif /* DACPO_SCENE_INTERNAL_H */
