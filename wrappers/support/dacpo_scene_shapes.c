/* SPDX-License-Identifier: BSD-3-Clause */
/* The scene kinds of dacpo_scene.h as lists of analytic patches: the patch
 * builder (quads with holes, boxes, cylinder patches, rings), each patch's area
 * and one uniform sample on it, and the scene definitions with their name table.
 * dacpo_scene.c apportions the points, samples, downsamples, fuses, adds noise. */
#include "dacpo_scene_internal.h"

#include <math.h>
#include <string.h>

/* ------------------------------------------------------------------------- */
/* Patches and the scene builder.                                             */

static void
set3(double d[3], double x, double y, double z)
{
  d[0] = x;
  d[1] = y;
  d[2] = z;
}

double
dacpo_scene_norm3(const double a[3])
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
  const double lu = dacpo_scene_norm3(p->u), lv = dacpo_scene_norm3(p->v);
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

double
dacpo_scene_prim_area(const scene_prim* p)
{
  switch (p->type) {
  case PRIM_QUAD: {
    double holes = 0.0;
    for (int i = 0; i < p->nholes; ++i)
      holes += (p->hole[i][1] - p->hole[i][0]) * (p->hole[i][3] - p->hole[i][2]);
    return dacpo_scene_norm3(p->u) * dacpo_scene_norm3(p->v) * fmax(0.0, 1.0 - holes);
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
void
dacpo_scene_prim_sample(const scene_prim* p, dacpo_rng* r, double pos[3], double nrm[3])
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
    dacpo_scene_rng_unit_vector(r, d);
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

const scene_entry dacpo_scene_table[DACPO_SCENE_KIND_COUNT] = {
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
