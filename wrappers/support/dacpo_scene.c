/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Synthetic scenes with ground-truth normals (see dacpo_scene.h).
 *
 * What it models: the evaluation inputs of the DACPO paper (section 6): open,
 * non-watertight indoor scans (ScanNet/SceneNN-like rooms with thin furniture),
 * their noisy variants (Gaussian displacement along a random direction, sigma
 * 0.004 / 0.008) and their randomly downsampled variants (100K / 10K points),
 * plus small analytic scenes for unit tests. Also the paper's score: share of
 * normals more than 90 degrees off the ground truth, up to one global sign.
 *
 * How: a scene is a list of analytic patches (rectangle with rectangular holes,
 * cylinder patch, annulus, sphere). Each patch gets a share of the points by the
 * largest-remainder rule on its area, so the total is exact and the density is
 * uniform; inside a patch the points are uniform by area (rejection for holes).
 * Geometry, downsampling and noise draw from separate xoshiro256** streams
 * derived from the seed, so the same seed gives the same surface points with or
 * without noise.
 *
 * Cost: O(n) time, 28 bytes per point (xyz, normals, part id).
 * Failure modes: invalid parameters (-1), out of memory (-2); never crashes,
 * prints or aborts.
 */
#include "dacpo_scene.h"

#include "dacpo_rng.h"
#include "dacpo_support_err.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SCENE_PI 3.14159265358979323846
#define SCENE_MAX_HOLES 6
#define SCENE_MAX_PRIMS 192
#define SCENE_MAX_OBJECTS 32
#define SCENE_MAX_POINTS ((size_t)1000000000)

enum { SCENE_ERR_INVALID = -1, SCENE_ERR_NOMEM = -2 };

/* Random streams: one per purpose so that, e.g., adding noise does not move the
 * underlying surface samples. */
enum {
  STREAM_GEOMETRY = 1,
  STREAM_DOWNSAMPLE = 2,
  STREAM_NOISE = 3,
  STREAM_SCRAMBLE = 4, /* dacpo_score.c */
  STREAM_FUSED = 5
};

/* ------------------------------------------------------------------------- */
/* RNG: the core's xoshiro256** (dacpo_rng.h), plus two distributions.        */

/* Standard normal, Marsaglia's polar method (second value discarded to keep the
 * generator stateless beyond the xoshiro state). */
static double
rng_gauss(dacpo_rng* r)
{
  double u, v, s;
  do {
    u = 2.0 * dacpo_rng_uniform(r) - 1.0;
    v = 2.0 * dacpo_rng_uniform(r) - 1.0;
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  return u * sqrt(-2.0 * log(s) / s);
}

/* Uniform unit vector: z uniform in [-1, 1] and uniform azimuth (Archimedes). */
static void
rng_unit_vector(dacpo_rng* r, double d[3])
{
  const double z = 2.0 * dacpo_rng_uniform(r) - 1.0;
  const double phi = 2.0 * SCENE_PI * dacpo_rng_uniform(r);
  const double rho = sqrt(fmax(0.0, 1.0 - z * z));
  d[0] = rho * cos(phi);
  d[1] = rho * sin(phi);
  d[2] = z;
}

/* ------------------------------------------------------------------------- */
/* Patches and the scene builder.                                             */

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

static void
set3(double d[3], double x, double y, double z)
{
  d[0] = x;
  d[1] = y;
  d[2] = z;
}

static double
norm3(const double a[3])
{
  return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

static void
begin_object(scene_builder* b, const char* name)
{
  if (b->num_objects >= SCENE_MAX_OBJECTS) {
    b->overflow = 1;
    return;
  }
  b->names[b->num_objects++] = name;
}

/* Returns a zeroed patch of the current object. On overflow, the spare slot is
 * returned so scene definitions need no checks; generation then fails. */
static scene_prim*
new_prim(scene_builder* b, prim_type type)
{
  scene_prim* p;
  if (b->count >= SCENE_MAX_PRIMS || b->num_objects == 0) {
    b->overflow = 1;
    p = &b->prims[SCENE_MAX_PRIMS];
  }
  else {
    p = &b->prims[b->count++];
  }
  memset(p, 0, sizeof(*p));
  p->type = type;
  p->object = b->num_objects > 0 ? (int32_t)(b->num_objects - 1) : 0;
  p->sign = 1.0;
  return p;
}

static scene_prim*
add_quad(scene_builder* b,
         const double c[3],
         const double u[3],
         const double v[3],
         const double n[3])
{
  scene_prim* p = new_prim(b, PRIM_QUAD);
  memcpy(p->c, c, sizeof(p->c));
  memcpy(p->u, u, sizeof(p->u));
  memcpy(p->v, v, sizeof(p->v));
  memcpy(p->w, n, sizeof(p->w));
  return p;
}

/* Axis-aligned quad helper: corner (x, y, z), edges (ux, uy, uz), (vx, vy, vz),
 * normal (nx, ny, nz). */
static scene_prim*
quad(scene_builder* b,
     double x,
     double y,
     double z,
     double ux,
     double uy,
     double uz,
     double vx,
     double vy,
     double vz,
     double nx,
     double ny,
     double nz)
{
  double c[3], u[3], v[3], n[3];
  set3(c, x, y, z);
  set3(u, ux, uy, uz);
  set3(v, vx, vy, vz);
  set3(n, nx, ny, nz);
  return add_quad(b, c, u, v, n);
}

/* Rectangular hole given in metres along u ([s0, s1]) and v ([t0, t1]). Holes of
 * one quad must be disjoint and inside it (their area is subtracted). */
static void
add_hole(scene_builder* b, scene_prim* p, double s0, double s1, double t0, double t1)
{
  const double lu = norm3(p->u), lv = norm3(p->v);
  if (p->type != PRIM_QUAD || p->nholes >= SCENE_MAX_HOLES || lu <= 0.0 || lv <= 0.0) {
    b->overflow = 1;
    return;
  }
  p->hole[p->nholes][0] = s0 / lu;
  p->hole[p->nholes][1] = s1 / lu;
  p->hole[p->nholes][2] = t0 / lv;
  p->hole[p->nholes][3] = t1 / lv;
  p->nholes++;
}

/* Faces of an axis-aligned box, normals outward, in the order +x, -x, +y, -y,
 * +z, -z. Bit (1 << face) of skip_mask leaves a face out (a face resting on the
 * floor or against another board is never seen by a scanner). */
enum { FACE_PX = 1, FACE_NX = 2, FACE_PY = 4, FACE_NY = 8, FACE_PZ = 16, FACE_NZ = 32 };

static void
add_box(scene_builder* b,
        double x0,
        double y0,
        double z0,
        double x1,
        double y1,
        double z1,
        unsigned skip_mask)
{
  const double dx = x1 - x0, dy = y1 - y0, dz = z1 - z0;
  if (!(skip_mask & FACE_PX))
    quad(b, x1, y0, z0, 0, dy, 0, 0, 0, dz, 1, 0, 0);
  if (!(skip_mask & FACE_NX))
    quad(b, x0, y0, z0, 0, dy, 0, 0, 0, dz, -1, 0, 0);
  if (!(skip_mask & FACE_PY))
    quad(b, x0, y1, z0, dx, 0, 0, 0, 0, dz, 0, 1, 0);
  if (!(skip_mask & FACE_NY))
    quad(b, x0, y0, z0, dx, 0, 0, 0, 0, dz, 0, -1, 0);
  if (!(skip_mask & FACE_PZ))
    quad(b, x0, y0, z1, dx, 0, 0, 0, dy, 0, 0, 0, 1);
  if (!(skip_mask & FACE_NZ))
    quad(b, x0, y0, z0, dx, 0, 0, 0, dy, 0, 0, 0, -1);
}

/* Cylinder patch around an axis through `base` along unit `axis`, with unit
 * frame e1, e2 (perpendicular to the axis); open: no caps. */
static scene_prim*
add_cylinder(scene_builder* b,
             const double base[3],
             const double axis[3],
             const double e1[3],
             const double e2[3],
             double radius,
             double height,
             double a0,
             double a1,
             double sign)
{
  scene_prim* p = new_prim(b, PRIM_CYLINDER);
  memcpy(p->c, base, sizeof(p->c));
  memcpy(p->w, axis, sizeof(p->w));
  memcpy(p->u, e1, sizeof(p->u));
  memcpy(p->v, e2, sizeof(p->v));
  p->r0 = radius;
  p->h = height;
  p->a0 = a0;
  p->a1 = a1;
  p->sign = sign;
  return p;
}

/* Full vertical open cylinder standing at (x, y, z0). */
static void
add_vcylinder(scene_builder* b,
              double x,
              double y,
              double z0,
              double radius,
              double height,
              double sign)
{
  double base[3], axis[3], e1[3], e2[3];
  set3(base, x, y, z0);
  set3(axis, 0, 0, 1);
  set3(e1, 1, 0, 0);
  set3(e2, 0, 1, 0);
  add_cylinder(b, base, axis, e1, e2, radius, height, 0.0, 2.0 * SCENE_PI, sign);
}

/* Horizontal annulus (ring) at height z, normal +z or -z. */
static void
add_hannulus(
    scene_builder* b, double x, double y, double z, double r0, double r1, double nz)
{
  scene_prim* p = new_prim(b, PRIM_ANNULUS);
  set3(p->c, x, y, z);
  set3(p->u, 1, 0, 0);
  set3(p->v, 0, 1, 0);
  set3(p->w, 0, 0, nz);
  p->r0 = r0;
  p->r1 = r1;
}

static double
prim_area(const scene_prim* p)
{
  switch (p->type) {
  case PRIM_QUAD: {
    double holes = 0.0;
    for (int i = 0; i < p->nholes; ++i)
      holes += (p->hole[i][1] - p->hole[i][0]) * (p->hole[i][3] - p->hole[i][2]);
    return norm3(p->u) * norm3(p->v) * fmax(0.0, 1.0 - holes);
  }
  case PRIM_CYLINDER:
    return p->r0 * (p->a1 - p->a0) * p->h;
  case PRIM_ANNULUS:
    return SCENE_PI * (p->r1 * p->r1 - p->r0 * p->r0);
  case PRIM_SPHERE:
    return 4.0 * SCENE_PI * p->r0 * p->r0;
  }
  return 0.0;
}

/* One uniform sample on patch p: position and unit normal, in double. */
static void
prim_sample(const scene_prim* p, dacpo_rng* r, double pos[3], double nrm[3])
{
  switch (p->type) {
  case PRIM_QUAD: {
    double s, t;
    int inside;
    /* Rejection from the holes; they cover a small part of every quad, so the
     * expected number of tries stays close to one. */
    do {
      s = dacpo_rng_uniform(r);
      t = dacpo_rng_uniform(r);
      inside = 0;
      for (int i = 0; i < p->nholes && !inside; ++i)
        inside = s >= p->hole[i][0] && s < p->hole[i][1] && t >= p->hole[i][2] &&
                 t < p->hole[i][3];
    } while (inside);
    for (int k = 0; k < 3; ++k) {
      pos[k] = p->c[k] + s * p->u[k] + t * p->v[k];
      nrm[k] = p->w[k];
    }
    return;
  }
  case PRIM_CYLINDER: {
    const double a = p->a0 + (p->a1 - p->a0) * dacpo_rng_uniform(r);
    const double h = p->h * dacpo_rng_uniform(r);
    const double ca = cos(a), sa = sin(a);
    for (int k = 0; k < 3; ++k) {
      const double radial = ca * p->u[k] + sa * p->v[k];
      pos[k] = p->c[k] + p->r0 * radial + h * p->w[k];
      nrm[k] = p->sign * radial;
    }
    return;
  }
  case PRIM_ANNULUS: {
    /* Radius by inverse CDF of the area measure rho d rho. */
    const double a = 2.0 * SCENE_PI * dacpo_rng_uniform(r);
    const double rho =
        sqrt(p->r0 * p->r0 + dacpo_rng_uniform(r) * (p->r1 * p->r1 - p->r0 * p->r0));
    const double ca = cos(a), sa = sin(a);
    for (int k = 0; k < 3; ++k) {
      pos[k] = p->c[k] + rho * (ca * p->u[k] + sa * p->v[k]);
      nrm[k] = p->w[k];
    }
    return;
  }
  case PRIM_SPHERE: {
    double d[3];
    rng_unit_vector(r, d);
    for (int k = 0; k < 3; ++k) {
      pos[k] = p->c[k] + p->r0 * d[k];
      nrm[k] = p->sign * d[k];
    }
    return;
  }
  }
}

/* ------------------------------------------------------------------------- */
/* Scenes. Each one is a small list of patches; see dacpo_scene.h.            */

/* Inner faces of the four walls of an axis-aligned room [x0,x1] x [y0,y1]
 * (height h), in the order y = y0, y = y1, x = x0, x = x1. */
static void
add_room_walls(scene_builder* b,
               double x0,
               double y0,
               double x1,
               double y1,
               double h,
               scene_prim* walls[4])
{
  walls[0] = quad(b, x0, y0, 0, x1 - x0, 0, 0, 0, 0, h, 0, 1, 0);
  walls[1] = quad(b, x0, y1, 0, x1 - x0, 0, 0, 0, 0, h, 0, -1, 0);
  walls[2] = quad(b, x0, y0, 0, 0, y1 - y0, 0, 0, 0, h, 1, 0, 0);
  walls[3] = quad(b, x1, y0, 0, 0, y1 - y0, 0, 0, 0, h, -1, 0, 0);
}

/* Chair at (cx, cy): 3 cm seat at 0.43-0.46 m, four 3 x 3 cm legs, 2 cm
 * backrest up to 0.9 m on the side away from where the sitter faces. */
static void
add_chair(scene_builder* b, double cx, double cy, int faces_plus_y)
{
  const double hs = 0.225, seat0 = 0.43, seat1 = 0.46, leg = 0.03, in = 0.01;
  add_box(b, cx - hs, cy - hs, seat0, cx + hs, cy + hs, seat1, 0);
  for (int i = 0; i < 4; ++i) {
    const double lx = (i & 1) ? cx + hs - in - leg : cx - hs + in;
    const double ly = (i & 2) ? cy + hs - in - leg : cy - hs + in;
    add_box(b, lx, ly, 0.0, lx + leg, ly + leg, seat0, FACE_PZ | FACE_NZ);
  }
  if (faces_plus_y)
    add_box(b, cx - hs, cy - hs, seat1, cx + hs, cy - hs + 0.02, 0.90, FACE_NZ);
  else
    add_box(b, cx - hs, cy + hs - 0.02, seat1, cx + hs, cy + hs, 0.90, FACE_NZ);
}

static void
scene_room(scene_builder* b)
{
  const double X = DACPO_SCENE_ROOM_SIZE_X, Y = DACPO_SCENE_ROOM_SIZE_Y;
  const double H = DACPO_SCENE_ROOM_HEIGHT;
  scene_prim* walls[4];
  scene_prim* floor_;

  /* Footprints of objects standing on the floor, and the cabinet's back against
   * the north wall: hidden from any scanner, so left out of floor and wall. */
  begin_object(b, "floor");
  floor_ = quad(b, 0, 0, 0, X, 0, 0, 0, Y, 0, 0, 0, 1);
  add_hole(b, floor_, 0.5, 1.3, 4.5, 5.0);    /* cabinet */
  add_hole(b, floor_, 1.5, 1.6, 0.5, 2.0);    /* partition */
  add_hole(b, floor_, 5.65, 5.95, 1.0, 1.02); /* bookshelf side panels */
  add_hole(b, floor_, 5.65, 5.95, 1.98, 2.0);

  begin_object(b, "walls");
  add_room_walls(b, 0, 0, X, Y, H, walls);
  add_hole(b, walls[0], 4.5, 5.4, 0.0, 2.05); /* door opening, south wall */
  add_hole(b, walls[1], 0.5, 1.3, 0.0, 0.9);  /* behind the cabinet */

  begin_object(b, "table");
  add_box(b, 2.2, 1.75, 0.71, 3.8, 2.65, 0.75, 0); /* 4 cm top, both faces */
  add_vcylinder(b, 2.28, 1.83, 0.0, 0.025, 0.71, 1.0);
  add_vcylinder(b, 3.72, 1.83, 0.0, 0.025, 0.71, 1.0);
  add_vcylinder(b, 2.28, 2.57, 0.0, 0.025, 0.71, 1.0);
  add_vcylinder(b, 3.72, 2.57, 0.0, 0.025, 0.71, 1.0);

  begin_object(b, "chair_1");
  add_chair(b, 3.0, 1.45, 1);
  begin_object(b, "chair_2");
  add_chair(b, 3.0, 2.95, 0);

  /* Bookshelf 5 cm off the east wall: two 2 cm side panels, five 2 cm shelves
   * between them (their ends touch the panels), a top board. */
  begin_object(b, "bookshelf");
  add_box(b, 5.65, 1.0, 0.0, 5.95, 1.02, 1.8, FACE_NZ);
  add_box(b, 5.65, 1.98, 0.0, 5.95, 2.0, 1.8, FACE_NZ);
  for (int i = 0; i < 5; ++i) {
    const double z = 0.05 + 0.4 * i;
    add_box(b, 5.65, 1.02, z, 5.95, 1.98, z + 0.02, FACE_PY | FACE_NY);
  }
  add_box(b, 5.65, 1.0, 1.8, 5.95, 2.0, 1.82, 0);

  /* Bin: 1.5 cm wall, no lid, no bottom: outer face, inner face (normals toward
   * the axis, into the bin's free interior) and the rim. */
  begin_object(b, "bin");
  add_vcylinder(b, 4.8, 4.2, 0.0, 0.16, 0.4, 1.0);
  add_vcylinder(b, 4.8, 4.2, 0.0, 0.145, 0.4, -1.0);
  add_hannulus(b, 4.8, 4.2, 0.4, 0.145, 0.16, 1.0);

  /* Free-standing double-sided partition, 10 cm thick, 1.8 m high. */
  begin_object(b, "partition");
  add_box(b, 1.5, 0.5, 0.0, 1.6, 2.0, 1.8, FACE_NZ);

  /* Thin 2 cm screen on two legs: a hard two-sided case. */
  begin_object(b, "screen");
  add_box(b, 4.0, 3.6, 0.6, 5.2, 3.62, 1.8, 0);
  add_box(b, 4.05, 3.595, 0.0, 4.08, 3.625, 0.6, FACE_PZ | FACE_NZ);
  add_box(b, 5.12, 3.595, 0.0, 5.15, 3.625, 0.6, FACE_PZ | FACE_NZ);

  /* Cabinet against the north wall: bottom and back faces hidden. */
  begin_object(b, "cabinet");
  add_box(b, 0.5, 4.5, 0.0, 1.3, 5.0, 0.9, FACE_NZ | FACE_PY);
}

static void
scene_plane(scene_builder* b)
{
  begin_object(b, "plane");
  quad(b, -1, -1, 0, 2, 0, 0, 0, 2, 0, 0, 0, 1);
}

static void
scene_sphere(scene_builder* b)
{
  scene_prim* p;
  begin_object(b, "sphere");
  p = new_prim(b, PRIM_SPHERE);
  set3(p->c, 0, 0, 0);
  p->r0 = 1.0;
  p->sign = 1.0;
}

static void
scene_two_rooms(scene_builder* b)
{
  const double H = 2.5, T = 0.1;
  scene_prim* face;

  begin_object(b, "room_a");
  quad(b, 0, 0, 0, 4, 0, 0, 0, 3, 0, 0, 0, 1);
  quad(b, 0, 0, 0, 4, 0, 0, 0, 0, H, 0, 1, 0);
  quad(b, 0, 3, 0, 4, 0, 0, 0, 0, H, 0, -1, 0);
  quad(b, 0, 0, 0, 0, 3, 0, 0, 0, H, 1, 0, 0);

  begin_object(b, "room_b");
  quad(b, 4 + T, 0, 0, 4, 0, 0, 0, 3, 0, 0, 0, 1);
  quad(b, 4 + T, 0, 0, 4, 0, 0, 0, 0, H, 0, 1, 0);
  quad(b, 4 + T, 3, 0, 4, 0, 0, 0, 0, H, 0, -1, 0);
  quad(b, 8 + T, 0, 0, 0, 3, 0, 0, 0, H, -1, 0, 0);

  /* Shared wall x in [4, 4.1], door y in [1.0, 1.9], z in [0, 2.0]: both faces
   * (each seen from its room), the top strip, the jambs, the lintel's underside
   * and the floor under the door, which links the two rooms' floors. */
  begin_object(b, "shared_wall");
  face = quad(b, 4, 0, 0, 0, 3, 0, 0, 0, H, -1, 0, 0);
  add_hole(b, face, 1.0, 1.9, 0.0, 2.0);
  face = quad(b, 4 + T, 0, 0, 0, 3, 0, 0, 0, H, 1, 0, 0);
  add_hole(b, face, 1.0, 1.9, 0.0, 2.0);
  quad(b, 4, 0, H, T, 0, 0, 0, 3, 0, 0, 0, 1);
  quad(b, 4, 1.0, 0, T, 0, 0, 0, 0, 2.0, 0, 1, 0);
  quad(b, 4, 1.9, 0, T, 0, 0, 0, 0, 2.0, 0, -1, 0);
  quad(b, 4, 1.0, 2.0, T, 0, 0, 0, 0.9, 0, 0, 0, -1);
  quad(b, 4, 1.0, 0, T, 0, 0, 0, 0.9, 0, 0, 0, 1);
}

static void
scene_board(scene_builder* b)
{
  begin_object(b, "board");
  add_box(b, -0.5, -0.3, -0.01, 0.5, 0.3, 0.01, 0);
}

static void
scene_half_cylinder(scene_builder* b)
{
  double base[3], axis[3], e1[3], e2[3];
  begin_object(b, "half_cylinder");
  set3(base, 0, -1, 0);
  set3(axis, 0, 1, 0);
  set3(e1, 1, 0, 0);
  set3(e2, 0, 0, 1);
  add_cylinder(b, base, axis, e1, e2, 1.0, 2.0, 0.0, SCENE_PI, 1.0);
}

static void
scene_s_sheet(scene_builder* b)
{
  double base[3], axis[3], e1[3], e2[3];
  begin_object(b, "s_sheet");
  set3(axis, 0, 1, 0);
  set3(e1, 1, 0, 0);
  set3(e2, 0, 0, 1);
  /* Lower arc: right half circle around (x, z) = (0, 0.5), outward normals.
   * Upper arc: left half circle around (0, 1.5), inward normals; at the joint
   * (0, 1) both give +z, so the sheet's orientation is consistent. */
  set3(base, 0, -1, 0.5);
  add_cylinder(b, base, axis, e1, e2, 0.5, 2.0, -0.5 * SCENE_PI, 0.5 * SCENE_PI, 1.0);
  set3(base, 0, -1, 1.5);
  add_cylinder(b, base, axis, e1, e2, 0.5, 2.0, 0.5 * SCENE_PI, 1.5 * SCENE_PI, -1.0);
}

static void
scene_box_open(scene_builder* b)
{
  scene_prim* walls[4];
  begin_object(b, "floor");
  quad(b, 0, 0, 0, 4, 0, 0, 0, 3, 0, 0, 0, 1);
  begin_object(b, "walls");
  add_room_walls(b, 0, 0, 4, 3, 2.5, walls);
}

/* Table on a floor (thin-structure known answer): 2.4 x 2 m floor, a 1.2 x 0.7
 * m top 2 cm thick at 0.72-0.74 m (all six faces), four 4 x 4 cm legs. The
 * floor under the legs is not sampled (buried). */
static void
scene_table_on_floor(scene_builder* b)
{
  const double leg = 0.04, x0 = 0.6, y0 = 0.65, x1 = 1.8, y1 = 1.35, z0 = 0.72;
  begin_object(b, "floor");
  scene_prim* floor = quad(b, 0, 0, 0, 2.4, 0, 0, 0, 2.0, 0, 0, 0, 1);
  begin_object(b, "table");
  add_box(b, x0, y0, z0, x1, y1, z0 + 0.02, 0);
  for (int i = 0; i < 4; ++i) {
    const double lx = (i & 1) ? x1 - 0.05 - leg : x0 + 0.05;
    const double ly = (i & 2) ? y1 - 0.05 - leg : y0 + 0.05;
    add_box(b, lx, ly, 0.0, lx + leg, ly + leg, z0, FACE_PZ | FACE_NZ);
    add_hole(b, floor, lx, lx + leg, ly, ly + leg);
  }
}

/* Free-standing open tube (a bin or lamp shade without bottom): outer radius
 * 0.15 m, wall 2 cm, 0.5 m tall; outer face, inner face (normals towards the
 * axis, into the free space inside) and both rims. */
static void
scene_tube(scene_builder* b)
{
  const double r1 = 0.15, r0 = 0.13, h = 0.5;
  begin_object(b, "tube");
  add_vcylinder(b, 0, 0, 0, r1, h, 1.0);
  add_vcylinder(b, 0, 0, 0, r0, h, -1.0);
  add_hannulus(b, 0, 0, h, r0, r1, 1.0);
  add_hannulus(b, 0, 0, 0, r0, r1, -1.0);
}

/* A 2 cm partition standing on the floor between two walls that face each
 * other: 4 x 3 m floor, inner faces of the walls x = 0 and x = 4 (2.5 m), the
 * partition x in [1.99, 2.01], y in [0.5, 2.5], 1.8 m tall (both faces, top
 * and ends; its foot on the floor is buried). */
static void
scene_partition(scene_builder* b)
{
  begin_object(b, "floor");
  scene_prim* floor = quad(b, 0, 0, 0, 4, 0, 0, 0, 3, 0, 0, 0, 1);
  add_hole(b, floor, 1.99, 2.01, 0.5, 2.5);
  begin_object(b, "walls");
  quad(b, 0, 0, 0, 0, 3, 0, 0, 0, 2.5, 1, 0, 0);
  quad(b, 4, 0, 0, 0, 3, 0, 0, 0, 2.5, -1, 0, 0);
  begin_object(b, "partition");
  add_box(b, 1.99, 0.5, 0.0, 2.01, 2.5, 1.8, FACE_NZ);
}

/* One floor of a building (multi-room known answer for scale-out): a 2 m
 * corridor along x (y in [0, 2]) between BUILDING_ROOMS rooms on each side,
 * 4 x 3.5 m each, walls 10 cm thick and 2.6 m high, no ceiling. Every room has
 * a 0.9 x 2.0 m door to the corridor in the middle of its front wall. Sampled,
 * as a scanner walking through would see them: floors, the inner faces of the
 * rooms and of the corridor, both faces of the walls between rooms and between
 * rooms and corridor (each face normal into the space it faces), the tops of
 * those inner walls, the doors' jambs, lintels and the floor under them. The
 * outer walls are one-sided (their outsides and tops are never seen). */
#define BUILDING_ROOMS 3

static void
building_room(scene_builder* b, int north, int i)
{
  static const char* const names[2][BUILDING_ROOMS] = {
      {"room_s1", "room_s2", "room_s3"}, {"room_n1", "room_n2", "room_n3"}};
  const double W = 4.0, D = 3.5, C = 2.0, T = 0.1, H = 2.6;
  const double door0 = 0.5 * W - 0.45, door1 = 0.5 * W + 0.45, door_h = 2.0;
  const double x0 = T + i * (W + T), x1 = x0 + W;
  /* interior y0..y1; the front wall slab lies between the room and y in [0, C] */
  const double y0 = north ? C + T : -T - D, y1 = y0 + D;
  const double front = north ? y0 : y1,
               slab = north ? C : 0.0;  /* slab: [C, C+T] or [-T, 0] */
  const double ny = north ? 1.0 : -1.0; /* from the front wall into the room */
  begin_object(b, names[north][i]);
  quad(b, x0, y0, 0, W, 0, 0, 0, D, 0, 0, 0, 1);
  quad(b, x0, y0, 0, 0, D, 0, 0, 0, H, 1, 0, 0);
  quad(b, x1, y0, 0, 0, D, 0, 0, 0, H, -1, 0, 0);
  quad(b, x0, north ? y1 : y0, 0, W, 0, 0, 0, 0, H, 0, -ny, 0);
  scene_prim* face = quad(b, x0, front, 0, W, 0, 0, 0, 0, H, 0, ny, 0);
  add_hole(b, face, door0, door1, 0.0, door_h);
  /* the door through the front slab y in [slab, slab + T] */
  const double sy = north ? slab : -T;
  quad(b, x0 + door0, sy, 0, 0, T, 0, 0, 0, door_h, 1, 0, 0);
  quad(b, x0 + door1, sy, 0, 0, T, 0, 0, 0, door_h, -1, 0, 0);
  quad(b, x0 + door0, sy, door_h, door1 - door0, 0, 0, 0, T, 0, 0, 0, -1);
  quad(b, x0 + door0, sy, 0, door1 - door0, 0, 0, 0, T, 0, 0, 0, 1);
  /* top of the front slab along this room; the wall to the next room (slab
   * x in [x1, x1 + T], through to the corridor) and its top */
  quad(b, x0, sy, H, W, 0, 0, 0, T, 0, 0, 0, 1);
  if (i + 1 < BUILDING_ROOMS)
    quad(b, x1, north ? C : y0, H, T, 0, 0, 0, D + T, 0, 0, 0, 1);
}

static void
scene_building(scene_builder* b)
{
  const double W = 4.0, C = 2.0, T = 0.1, H = 2.6;
  const double L = BUILDING_ROOMS * (W + T) + T; /* outer x extent */
  for (int north = 0; north < 2; ++north)
    for (int i = 0; i < BUILDING_ROOMS; ++i)
      building_room(b, north, i);
  begin_object(b, "corridor");
  quad(b, T, 0, 0, L - 2 * T, 0, 0, 0, C, 0, 0, 0, 1);
  quad(b, T, 0, 0, 0, C, 0, 0, 0, H, 1, 0, 0);
  quad(b, L - T, 0, 0, 0, C, 0, 0, 0, H, -1, 0, 0);
  /* the corridor faces of the front slabs, one door per room */
  scene_prim* south = quad(b, T, 0, 0, L - 2 * T, 0, 0, 0, 0, H, 0, 1, 0);
  scene_prim* north = quad(b, T, C, 0, L - 2 * T, 0, 0, 0, 0, H, 0, -1, 0);
  for (int i = 0; i < BUILDING_ROOMS; ++i) {
    const double d0 = i * (W + T) + 0.5 * W - 0.45;
    add_hole(b, south, d0, d0 + 0.9, 0.0, 2.0);
    add_hole(b, north, d0, d0 + 0.9, 0.0, 2.0);
  }
}

typedef struct scene_entry {
  const char* name;
  void (*build)(scene_builder*);
} scene_entry;

static const scene_entry scene_table[DACPO_SCENE_KIND_COUNT] = {
    {"room", scene_room},
    {"plane", scene_plane},
    {"sphere", scene_sphere},
    {"two_rooms", scene_two_rooms},
    {"board", scene_board},
    {"half_cylinder", scene_half_cylinder},
    {"s_sheet", scene_s_sheet},
    {"box", scene_box_open},
    {"table", scene_table_on_floor},
    {"tube", scene_tube},
    {"partition", scene_partition},
    {"building", scene_building},
};

/* ------------------------------------------------------------------------- */
/* Public functions.                                                          */

const char*
dacpo_scene_kind_name(unsigned kind)
{
  return kind < DACPO_SCENE_KIND_COUNT ? scene_table[kind].name : NULL;
}

int
dacpo_scene_kind_from_name(const char* name, unsigned* kind)
{
  if (!name || !kind)
    return -1;
  for (unsigned i = 0; i < DACPO_SCENE_KIND_COUNT; ++i) {
    if (strcmp(name, scene_table[i].name) == 0) {
      *kind = i;
      return 0;
    }
  }
  return -1;
}

void
dacpo_scene_params_init(dacpo_scene_params* params)
{
  if (!params)
    return;
  memset(params, 0, sizeof(*params));
  params->kind = DACPO_SCENE_ROOM;
  params->target_points = 100000;
  params->noise_sigma = 0.0;
  params->downsample_to = 0;
  params->seed = 1;
  params->fused_views = 0;
  params->fused_shift = 0.01;
  params->fused_angle = 0.2;
}

void
dacpo_scene_free(dacpo_scene* scene)
{
  if (!scene)
    return;
  free(scene->xyz);
  free(scene->normals);
  free(scene->part);
  free(scene->part_object);
  free((void*)scene->object_name);
  memset(scene, 0, sizeof(*scene));
}

typedef struct quota_item {
  double frac;
  size_t index;
} quota_item;

/* Larger fractional part first; ties by index so the order is deterministic. */
static int
quota_cmp(const void* a, const void* b)
{
  const quota_item* x = (const quota_item*)a;
  const quota_item* y = (const quota_item*)b;
  if (x->frac != y->frac)
    return x->frac > y->frac ? -1 : 1;
  return x->index < y->index ? -1 : (x->index > y->index ? 1 : 0);
}

/* Largest-remainder apportionment of n points by area: exact total, each patch
 * within one point of its area share. */
static void
apportion(const double* area, size_t count, size_t n, size_t* out, quota_item* items)
{
  double total = 0.0;
  size_t assigned = 0;
  for (size_t i = 0; i < count; ++i)
    total += area[i];
  for (size_t i = 0; i < count; ++i) {
    const double q = (double)n * area[i] / total;
    double fl = floor(q);
    if (fl > (double)(n - assigned))
      fl = (double)(n - assigned);
    out[i] = (size_t)fl;
    assigned += out[i];
    items[i].frac = q - fl;
    items[i].index = i;
  }
  qsort(items, count, sizeof(*items), quota_cmp);
  for (size_t i = 0; assigned < n; i = (i + 1) % count) {
    out[items[i].index]++;
    assigned++;
  }
}

/* Keep exactly k of the n points, uniformly, in their original order (Knuth's
 * selection sampling, algorithm S). */
static void
downsample(dacpo_scene* s, size_t k, uint64_t seed)
{
  dacpo_rng r;
  size_t kept = 0;
  dacpo_rng_seed(&r, seed, STREAM_DOWNSAMPLE);
  for (size_t i = 0; i < s->n && kept < k; ++i) {
    if ((double)(s->n - i) * dacpo_rng_uniform(&r) < (double)(k - kept)) {
      memmove(s->xyz + 3 * kept, s->xyz + 3 * i, 3 * sizeof(float));
      memmove(s->normals + 3 * kept, s->normals + 3 * i, 3 * sizeof(float));
      s->part[kept] = s->part[i];
      kept++;
    }
  }
  s->n = kept;
  /* Shrinking; on a failed realloc the larger block stays valid. */
  {
    float* p = (float*)realloc(s->xyz, 3 * kept * sizeof(float));
    if (p)
      s->xyz = p;
    p = (float*)realloc(s->normals, 3 * kept * sizeof(float));
    if (p)
      s->normals = p;
  }
  {
    int32_t* q = (int32_t*)realloc(s->part, kept * sizeof(int32_t));
    if (q)
      s->part = q;
  }
}

/* Paper section 6: displacement sigma * N(0, 1) along a uniformly random
 * direction (mean length 0.8 sigma); normals keep the ground truth. */
static void
add_noise(dacpo_scene* s, double sigma, uint64_t seed)
{
  dacpo_rng r;
  dacpo_rng_seed(&r, seed, STREAM_NOISE);
  for (size_t i = 0; i < s->n; ++i) {
    double d[3];
    const double g = sigma * rng_gauss(&r);
    rng_unit_vector(&r, d);
    for (int k = 0; k < 3; ++k)
      s->xyz[3 * i + k] = (float)((double)s->xyz[3 * i + k] + g * d[k]);
  }
}

/* Views fused with a registration error: point i belongs to a random one of
 * `views`; view v > 0 is turned by `angle_deg` about a random axis through the
 * scene's centre and moved by `shift` in a random direction (its normals turn
 * with it, so the ground truth stays that of the surface each copy shows). */
static void
fuse_views(dacpo_scene* s, unsigned views, double shift, double angle_deg, uint64_t seed)
{
  dacpo_rng r;
  dacpo_rng_seed(&r, seed, STREAM_FUSED);
  double c[3] = {0.0, 0.0, 0.0};
  for (size_t i = 0; i < s->n; ++i)
    for (int k = 0; k < 3; ++k)
      c[k] += (double)s->xyz[3 * i + k] / (double)s->n;
  double rot[DACPO_SCENE_MAX_FUSED_VIEWS][9], move[DACPO_SCENE_MAX_FUSED_VIEWS][3];
  for (unsigned v = 0; v < views; ++v) {
    double a[3], t[3];
    rng_unit_vector(&r, a);
    rng_unit_vector(&r, t);
    /* Rodrigues: R = I + sin(th) K + (1 - cos(th)) K^2, K the cross matrix of a */
    const double th = v == 0 ? 0.0 : angle_deg * (3.14159265358979323846 / 180.0);
    const double K[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double k2 = 0.0;
        for (int m = 0; m < 3; ++m)
          k2 += K[3 * i + m] * K[3 * m + j];
        rot[v][3 * i + j] = (i == j) + sin(th) * K[3 * i + j] + (1.0 - cos(th)) * k2;
      }
    for (int k = 0; k < 3; ++k)
      move[v][k] = v == 0 ? 0.0 : shift * t[k];
  }
  for (size_t i = 0; i < s->n; ++i) {
    const size_t v = dacpo_rng_below(&r, views);
    float* p = s->xyz + 3 * i;
    float* q = s->normals + 3 * i;
    const double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    const double m[3] = {q[0], q[1], q[2]};
    for (int k = 0; k < 3; ++k) {
      const double* R = rot[v] + 3 * k;
      p[k] = (float)(c[k] + R[0] * d[0] + R[1] * d[1] + R[2] * d[2] + move[v][k]);
      q[k] = (float)(R[0] * m[0] + R[1] * m[1] + R[2] * m[2]);
    }
  }
}

/* The parameters dacpo_scene_generate accepts (0, or SCENE_ERR_INVALID with
 * a message). */
static int
check_scene_params(const dacpo_scene_params* params, char* err, size_t errlen)
{
  const size_t n = params->target_points;
  if (params->kind >= DACPO_SCENE_KIND_COUNT) {
    dacpo_support_err(err,
                      errlen,
                      "unknown scene kind %u (valid: 0..%d)",
                      params->kind,
                      DACPO_SCENE_KIND_COUNT - 1);
    return SCENE_ERR_INVALID;
  }
  if (n == 0 || n > SCENE_MAX_POINTS || n > SIZE_MAX / (3 * sizeof(float))) {
    dacpo_support_err(
        err, errlen, "target_points %zu out of range (1..%zu)", n, SCENE_MAX_POINTS);
    return SCENE_ERR_INVALID;
  }
  if (!(params->noise_sigma >= 0.0) || !isfinite(params->noise_sigma)) {
    dacpo_support_err(
        err, errlen, "noise_sigma %g must be finite and >= 0", params->noise_sigma);
    return SCENE_ERR_INVALID;
  }
  if (params->fused_views > DACPO_SCENE_MAX_FUSED_VIEWS ||
      !(params->fused_shift >= 0.0) || !isfinite(params->fused_shift) ||
      !(params->fused_angle >= 0.0) || !isfinite(params->fused_angle)) {
    dacpo_support_err(err,
                      errlen,
                      "fused views %u (at most %d), shift %g and angle %g must be finite and >= 0",
                      params->fused_views,
                      DACPO_SCENE_MAX_FUSED_VIEWS,
                      params->fused_shift,
                      params->fused_angle);
    return SCENE_ERR_INVALID;
  }
  if (params->downsample_to > n) {
    dacpo_support_err(err,
                      errlen,
                      "downsample_to %zu exceeds target_points %zu",
                      params->downsample_to,
                      n);
    return SCENE_ERR_INVALID;
  }
  return 0;
}

/* counts[i] points on patch i, in patch order, from the geometry stream; then
 * the part -> object table and the object names. */
static void
sample_patches(const scene_builder* b,
               const size_t* counts,
               uint64_t seed,
               dacpo_scene* s)
{
  dacpo_rng r;
  size_t next = 0;
  dacpo_rng_seed(&r, seed, STREAM_GEOMETRY);
  for (size_t i = 0; i < b->count; ++i) {
    for (size_t j = 0; j < counts[i]; ++j, ++next) {
      double pos[3] = {0.0, 0.0, 0.0}, nrm[3] = {0.0, 0.0, 1.0}, len;
      prim_sample(&b->prims[i], &r, pos, nrm);
      len = norm3(nrm);
      for (int k = 0; k < 3; ++k) {
        s->xyz[3 * next + k] = (float)pos[k];
        s->normals[3 * next + k] = (float)(nrm[k] / len);
      }
      s->part[next] = (int32_t)i;
    }
  }
  s->n = next;
  s->num_parts = b->count;
  s->num_objects = b->num_objects;
  for (size_t i = 0; i < b->count; ++i)
    s->part_object[i] = b->prims[i].object;
  for (size_t i = 0; i < b->num_objects; ++i)
    s->object_name[i] = b->names[i];
}

int
dacpo_scene_generate(const dacpo_scene_params* params,
                     dacpo_scene* out,
                     char* err,
                     size_t errlen)
{
  scene_builder b;
  double* area = NULL;
  size_t* counts = NULL;
  quota_item* items = NULL;
  dacpo_scene s;
  size_t n;
  int status = 0;

  if (err && errlen > 0)
    err[0] = '\0';
  if (out)
    memset(out, 0, sizeof(*out));
  if (!params || !out) {
    dacpo_support_err(
        err, errlen, "dacpo_scene_generate: %s is NULL", !params ? "params" : "out");
    return SCENE_ERR_INVALID;
  }
  if ((status = check_scene_params(params, err, errlen)) != 0)
    return status;
  n = params->target_points;

  memset(&b, 0, sizeof(b));
  memset(&s, 0, sizeof(s));
  b.prims = (scene_prim*)malloc((SCENE_MAX_PRIMS + 1) * sizeof(scene_prim));
  if (!b.prims)
    goto oom;
  scene_table[params->kind].build(&b);
  if (b.overflow || b.count == 0) {
    dacpo_support_err(err,
                      errlen,
                      "internal error: scene '%s' exceeds the builder's limits",
                      scene_table[params->kind].name);
    status = SCENE_ERR_INVALID;
    goto done;
  }

  area = (double*)malloc(b.count * sizeof(double));
  counts = (size_t*)malloc(b.count * sizeof(size_t));
  items = (quota_item*)malloc(b.count * sizeof(quota_item));
  s.xyz = (float*)malloc(3 * n * sizeof(float));
  s.normals = (float*)malloc(3 * n * sizeof(float));
  s.part = (int32_t*)malloc(n * sizeof(int32_t));
  s.part_object = (int32_t*)malloc(b.count * sizeof(int32_t));
  s.object_name = (const char**)malloc(b.num_objects * sizeof(const char*));
  if (!area || !counts || !items || !s.xyz || !s.normals || !s.part || !s.part_object ||
      !s.object_name)
    goto oom;

  for (size_t i = 0; i < b.count; ++i)
    area[i] = prim_area(&b.prims[i]);
  apportion(area, b.count, n, counts, items);
  sample_patches(&b, counts, params->seed, &s);
  if (params->downsample_to > 0 && params->downsample_to < s.n)
    downsample(&s, params->downsample_to, params->seed);
  if (params->fused_views > 1)
    fuse_views(&s, params->fused_views, params->fused_shift, params->fused_angle, params->seed);
  if (params->noise_sigma > 0.0)
    add_noise(&s, params->noise_sigma, params->seed);

  *out = s;
  memset(&s, 0, sizeof(s));
  goto done;

oom:
  dacpo_support_err(err, errlen, "out of memory generating %zu points", n);
  status = SCENE_ERR_NOMEM;
done:
  dacpo_scene_free(&s);
  free(area);
  free(counts);
  free(items);
  free(b.prims);
  return status;
}

size_t
dacpo_scene_scramble_signs(const dacpo_scene* scene,
                           float* normals_out,
                           uint64_t seed,
                           double fraction)
{
  if (!scene)
    return 0;
  return dacpo_scramble_signs(scene->normals, normals_out, scene->n, seed, fraction);
}

/* ------------------------------------------------------------------------- */
/* Two parallel sheets facing away from each other (thin-structure tests).    */

int
dacpo_scene_parallel_sheets(double size,
                            double spacing,
                            double gap,
                            double sigma,
                            uint64_t seed,
                            dacpo_scene* out,
                            char* err,
                            size_t errlen)
{
  if (!out || !(size > 0.0) || !(spacing > 0.0) || !(gap > 0.0) || !(sigma >= 0.0) ||
      size / spacing > 2000.0) {
    if (err && errlen)
      snprintf(err, errlen, "parallel sheets: bad argument");
    return -1;
  }
  memset(out, 0, sizeof(*out));
  const size_t m = (size_t)(size / spacing) + 1, n = 2 * m * m;
  out->xyz = malloc(3 * n * sizeof(float));
  out->normals = malloc(3 * n * sizeof(float));
  out->part = malloc(n * sizeof(int32_t));
  out->part_object = malloc(2 * sizeof(int32_t));
  out->object_name = malloc(sizeof(const char*));
  if (!out->xyz || !out->normals || !out->part || !out->part_object ||
      !out->object_name) {
    dacpo_scene_free(out);
    if (err && errlen)
      snprintf(err, errlen, "parallel sheets: out of memory");
    return -1;
  }
  dacpo_rng r;
  dacpo_rng_seed(&r, seed, 17);
  size_t k = 0;
  for (int sheet = 0; sheet < 2; ++sheet)
    for (size_t a = 0; a < m; ++a)
      for (size_t b = 0; b < m; ++b, ++k) {
        /* jittered grid, so the two sheets' points do not sit exactly above
         * each other; the lower sheet faces -z, the upper +z */
        double p[3] = {((double)a + 0.5 * (dacpo_rng_uniform(&r) - 0.5)) * spacing,
                       ((double)b + 0.5 * (dacpo_rng_uniform(&r) - 0.5)) * spacing,
                       sheet ? gap : 0.0};
        if (sigma > 0.0) {
          double d[3];
          const double g = sigma * rng_gauss(&r);
          rng_unit_vector(&r, d);
          for (int c = 0; c < 3; ++c)
            p[c] += g * d[c];
        }
        for (int c = 0; c < 3; ++c) {
          out->xyz[3 * k + c] = (float)p[c];
          out->normals[3 * k + c] = c == 2 ? (sheet ? 1.0f : -1.0f) : 0.0f;
        }
        out->part[k] = sheet;
      }
  out->n = n;
  out->num_parts = 2;
  out->part_object[0] = out->part_object[1] = 0;
  out->num_objects = 1;
  out->object_name[0] = "board";
  return 0;
}
