/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Depth-camera views of a scene (dacpo_scene_params::views): registered RGB-D
 * frames concatenated. Each camera (60 x 45 degrees, 0.3..6 m) stands at a
 * seeded place in free space (rooms: inside the room at 1.2..1.8 m; objects: on
 * a sphere around the bounding box) and looks at a seeded surface point. Its
 * points are the first hits of rays drawn uniformly by solid angle inside the
 * field of view, cast against every patch with exact ray-quad (holes),
 * ray-cylinder, ray-annulus and ray-sphere intersections: so a point is kept
 * only where the camera sees it unoccluded, with a surface density proportional
 * to cos(incidence) / range^2, exactly. The view's share of the points comes
 * out view by view, each view row by row as a depth image's pixels (rows of
 * an image with as many pixels as rays drawn, top to bottom, each left to
 * right: registered frames concatenated keep that order, and the frames'
 * sensors are found from it); each view but the first is then moved by its pose error
 * (a shift in a random direction, a turn about a random axis through the
 * camera). Ground-truth normal: the patch normal turned towards the point's
 * camera, turned with the pose error.
 *
 * Cost: O(points x patches) ray-patch tests. Deterministic per seed.
 */
#include "dacpo_rng.h"
#include "dacpo_scene_internal.h"
#include "dacpo_support_err.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { STREAM_VIEWS = 6 };

#define VIEW_NEAR 0.3
#define VIEW_FAR 6.0
#define VIEW_TAN_X 0.57735026918962576 /* tan(30 deg): 60 deg wide */
#define VIEW_TAN_Y 0.41421356237309503 /* tan(22.5 deg): 45 deg high */
#define VIEW_TMIN 1e-7
#define VIEW_PLACE_TRIES 2000

typedef struct view_cam {
  double eye[3], target[3];
  double fwd[3], right[3], up[3];
  double rot[9], move[3]; /* pose error: p -> eye + rot (p - eye) + move */
} view_cam;

/* The patches, their cumulative areas (area-weighted picks) and bounds. */
typedef struct view_ctx {
  const scene_builder* b;
  double cum_area[SCENE_MAX_PRIMS];
  double lo[3], hi[3];
} view_ctx;

static double
dot3(const double a[3], const double b[3])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void
cross3(const double a[3], const double b[3], double c[3])
{
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static int
normalize3(double a[3])
{
  const double l = dacpo_scene_norm3(a);
  if (!(l > 1e-12))
    return -1;
  for (int k = 0; k < 3; ++k)
    a[k] /= l;
  return 0;
}

/* ------------------------------------------------------------------------- */
/* Exact ray-patch intersections: ray o + t d (d unit), t in (tmin, tmax);     */
/* each returns the hit's t, or -1.                                           */

static double
hit_quad(const scene_prim* p, const double o[3], const double d[3], double tmin, double tmax)
{
  double nrm[3], q[3];
  cross3(p->u, p->v, nrm);
  const double dn = dot3(d, nrm);
  if (fabs(dn) < 1e-15)
    return -1.0;
  const double oc[3] = {p->c[0] - o[0], p->c[1] - o[1], p->c[2] - o[2]};
  const double t = dot3(oc, nrm) / dn;
  if (!(t > tmin && t < tmax))
    return -1.0;
  for (int k = 0; k < 3; ++k)
    q[k] = o[k] + t * d[k] - p->c[k];
  const double s = dot3(q, p->u) / dot3(p->u, p->u);
  const double w = dot3(q, p->v) / dot3(p->v, p->v);
  if (s < 0.0 || s >= 1.0 || w < 0.0 || w >= 1.0)
    return -1.0;
  for (int i = 0; i < p->nholes; ++i)
    if (s >= p->hole[i][0] && s < p->hole[i][1] && w >= p->hole[i][2] && w < p->hole[i][3])
      return -1.0;
  return t;
}

/* Angle a in [a0, a0 + 2 pi) lies in the patch's [a0, a1]. */
static int
in_angle_range(const scene_prim* p, double a)
{
  while (a < p->a0)
    a += 2.0 * SCENE_PI;
  while (a >= p->a0 + 2.0 * SCENE_PI)
    a -= 2.0 * SCENE_PI;
  return a <= p->a1;
}

static double
hit_cylinder(const scene_prim* p,
             const double o[3],
             const double d[3],
             double tmin,
             double tmax)
{
  const double oc[3] = {o[0] - p->c[0], o[1] - p->c[1], o[2] - p->c[2]};
  const double x0 = dot3(oc, p->u), y0 = dot3(oc, p->v), z0 = dot3(oc, p->w);
  const double dx = dot3(d, p->u), dy = dot3(d, p->v), dz = dot3(d, p->w);
  const double a = dx * dx + dy * dy;
  const double bh = x0 * dx + y0 * dy, c = x0 * x0 + y0 * y0 - p->r0 * p->r0;
  const double disc = bh * bh - a * c;
  if (a < 1e-18 || disc < 0.0)
    return -1.0;
  const double sq = sqrt(disc);
  const double roots[2] = {(-bh - sq) / a, (-bh + sq) / a};
  for (int i = 0; i < 2; ++i) {
    const double t = roots[i], z = z0 + t * dz;
    if (!(t > tmin && t < tmax) || z < 0.0 || z > p->h)
      continue;
    if (in_angle_range(p, atan2(y0 + t * dy, x0 + t * dx)))
      return t;
  }
  return -1.0;
}

static double
hit_annulus(const scene_prim* p,
            const double o[3],
            const double d[3],
            double tmin,
            double tmax)
{
  const double dn = dot3(d, p->w);
  if (fabs(dn) < 1e-15)
    return -1.0;
  const double oc[3] = {p->c[0] - o[0], p->c[1] - o[1], p->c[2] - o[2]};
  const double t = dot3(oc, p->w) / dn;
  if (!(t > tmin && t < tmax))
    return -1.0;
  double q[3];
  for (int k = 0; k < 3; ++k)
    q[k] = o[k] + t * d[k] - p->c[k];
  const double rho = dacpo_scene_norm3(q);
  return rho >= p->r0 && rho <= p->r1 ? t : -1.0;
}

static double
hit_sphere(const scene_prim* p, const double o[3], const double d[3], double tmin, double tmax)
{
  const double oc[3] = {o[0] - p->c[0], o[1] - p->c[1], o[2] - p->c[2]};
  const double bh = dot3(oc, d), c = dot3(oc, oc) - p->r0 * p->r0;
  const double disc = bh * bh - c;
  if (disc < 0.0)
    return -1.0;
  const double sq = sqrt(disc);
  if (-bh - sq > tmin && -bh - sq < tmax)
    return -bh - sq;
  return -bh + sq > tmin && -bh + sq < tmax ? -bh + sq : -1.0;
}

/* The nearest patch the ray meets in (VIEW_TMIN, tmax): its index (or -1) and
 * the hit's t in *t_out. */
static int
nearest_hit(const scene_builder* b, const double o[3], const double d[3], double tmax, double* t_out)
{
  int best = -1;
  for (size_t i = 0; i < b->count; ++i) {
    const scene_prim* p = &b->prims[i];
    double t = -1.0;
    switch (p->type) {
    case PRIM_QUAD: t = hit_quad(p, o, d, VIEW_TMIN, tmax); break;
    case PRIM_CYLINDER: t = hit_cylinder(p, o, d, VIEW_TMIN, tmax); break;
    case PRIM_ANNULUS: t = hit_annulus(p, o, d, VIEW_TMIN, tmax); break;
    case PRIM_SPHERE: t = hit_sphere(p, o, d, VIEW_TMIN, tmax); break;
    }
    if (t > 0.0) {
      tmax = t;
      best = (int)i;
    }
  }
  *t_out = tmax;
  return best;
}

/* Unit normal of patch p at its point x (into free space, as sampled). */
static void
prim_normal(const scene_prim* p, const double x[3], double n[3])
{
  double q[3] = {x[0] - p->c[0], x[1] - p->c[1], x[2] - p->c[2]};
  if (p->type == PRIM_CYLINDER) {
    const double h = dot3(q, p->w);
    for (int k = 0; k < 3; ++k)
      q[k] -= h * p->w[k];
  }
  for (int k = 0; k < 3; ++k)
    n[k] = p->type == PRIM_QUAD || p->type == PRIM_ANNULUS ? p->w[k] : p->sign * q[k];
  if (normalize3(n) != 0)
    memcpy(n, p->w, sizeof(double) * 3);
}

/* ------------------------------------------------------------------------- */
/* Camera placement.                                                          */

static int
is_room_kind(unsigned kind)
{
  return kind == DACPO_SCENE_ROOM || kind == DACPO_SCENE_TWO_ROOMS ||
         kind == DACPO_SCENE_BUILDING || kind == DACPO_SCENE_BOX_OPEN;
}

/* A uniform point on the surfaces (area-weighted patch, uniform inside). */
static void
surface_point(const view_ctx* cx, dacpo_rng* r, double x[3])
{
  const size_t m = cx->b->count;
  const double a = dacpo_rng_uniform(r) * cx->cum_area[m - 1];
  size_t i = 0;
  double nrm[3];
  while (i + 1 < m && cx->cum_area[i] <= a)
    ++i;
  dacpo_scene_prim_sample(&cx->b->prims[i], r, x, nrm);
}

static void
init_ctx(view_ctx* cx, const scene_builder* b, dacpo_rng* r)
{
  double acc = 0.0;
  cx->b = b;
  for (size_t i = 0; i < b->count; ++i)
    cx->cum_area[i] = acc += dacpo_scene_prim_area(&b->prims[i]);
  for (int k = 0; k < 3; ++k) {
    cx->lo[k] = HUGE_VAL;
    cx->hi[k] = -HUGE_VAL;
  }
  for (size_t i = 0; i < b->count; ++i)
    for (int j = 0; j < 64; ++j) {
      double x[3], nrm[3];
      dacpo_scene_prim_sample(&b->prims[i], r, x, nrm);
      for (int k = 0; k < 3; ++k) {
        cx->lo[k] = fmin(cx->lo[k], x[k]);
        cx->hi[k] = fmax(cx->hi[k], x[k]);
      }
    }
}

/* Free space: no patch within VIEW_NEAR along 26 directions, none seen from
 * behind (inside a solid, behind a wall), and surfaces in range along at least
 * need_hits of them. */
static int
in_free_space(const scene_builder* b, const double eye[3], int need_hits)
{
  int hits = 0;
  for (int i = 0; i < 27; ++i) {
    double d[3] = {(double)(i % 3) - 1.0, (double)(i / 3 % 3) - 1.0, (double)(i / 9) - 1.0};
    double t, n[3], x[3];
    if (normalize3(d) != 0)
      continue;
    const int h = nearest_hit(b, eye, d, 1e30, &t);
    if (h < 0)
      continue;
    for (int k = 0; k < 3; ++k)
      x[k] = eye[k] + t * d[k];
    prim_normal(&b->prims[h], x, n);
    if (t < VIEW_NEAR || dot3(n, d) > 0.0)
      return 0;
    hits += t < VIEW_FAR;
  }
  return hits >= need_hits;
}

/* The camera's place: a room's inside at 1.2..1.8 m, or a sphere around an
 * object's bounding box; retried until in free space. */
static int
place_eye(const view_ctx* cx, unsigned kind, dacpo_rng* r, double eye[3])
{
  double c[3], half[3];
  for (int k = 0; k < 3; ++k) {
    c[k] = 0.5 * (cx->lo[k] + cx->hi[k]);
    half[k] = 0.5 * (cx->hi[k] - cx->lo[k]);
  }
  const double rad = 1.2 * dacpo_scene_norm3(half) + 0.5;
  for (int tries = 0; tries < VIEW_PLACE_TRIES; ++tries) {
    if (is_room_kind(kind)) {
      for (int k = 0; k < 2; ++k)
        eye[k] = cx->lo[k] + VIEW_NEAR +
                 dacpo_rng_uniform(r) * fmax(0.0, cx->hi[k] - cx->lo[k] - 2.0 * VIEW_NEAR);
      eye[2] = cx->lo[2] + 1.2 + 0.6 * dacpo_rng_uniform(r);
    }
    else {
      double u[3];
      dacpo_scene_rng_unit_vector(r, u);
      for (int k = 0; k < 3; ++k)
        eye[k] = c[k] + rad * u[k];
    }
    if (in_free_space(cx->b, eye, is_room_kind(kind) ? 4 : 0))
      return 0;
  }
  return -1;
}

/* Camera v: place, a target 1..5 m away (objects: any surface point), the
 * frame, the pose error (none for view 0). */
static int
make_camera(const view_ctx* cx, const dacpo_scene_params* prm, unsigned v, dacpo_rng* r, view_cam* cam)
{
  static const double zup[3] = {0.0, 0.0, 1.0}, xax[3] = {1.0, 0.0, 0.0};
  double axis[3], dir[3];
  if (place_eye(cx, prm->kind, r, cam->eye) != 0)
    return -1;
  for (int tries = 0; tries < VIEW_PLACE_TRIES; ++tries) {
    surface_point(cx, r, cam->target);
    const double dist = sqrt((cam->target[0] - cam->eye[0]) * (cam->target[0] - cam->eye[0]) +
                             (cam->target[1] - cam->eye[1]) * (cam->target[1] - cam->eye[1]) +
                             (cam->target[2] - cam->eye[2]) * (cam->target[2] - cam->eye[2]));
    if (!is_room_kind(prm->kind) || (dist >= 1.0 && dist <= 5.0))
      break;
  }
  for (int k = 0; k < 3; ++k)
    cam->fwd[k] = cam->target[k] - cam->eye[k];
  if (normalize3(cam->fwd) != 0)
    cam->fwd[2] = 1.0;
  cross3(cam->fwd, zup, cam->right);
  if (normalize3(cam->right) != 0) {
    cross3(cam->fwd, xax, cam->right);
    normalize3(cam->right);
  }
  cross3(cam->right, cam->fwd, cam->up);
  dacpo_scene_rng_unit_vector(r, axis);
  dacpo_scene_rng_unit_vector(r, dir);
  dacpo_scene_rotation(axis, v == 0 ? 0.0 : prm->view_angle * (SCENE_PI / 180.0), cam->rot);
  for (int k = 0; k < 3; ++k)
    cam->move[k] = v == 0 ? 0.0 : prm->view_shift * dir[k];
  return 0;
}

/* ------------------------------------------------------------------------- */
/* Sampling.                                                                  */

/* A ray direction uniform by solid angle inside the field of view: uniform in
 * the cone around it, rejected outside the rectangle. */
static void
draw_ray(const view_cam* cam, dacpo_rng* r, double d[3])
{
  const double cmin = 1.0 / sqrt(1.0 + VIEW_TAN_X * VIEW_TAN_X + VIEW_TAN_Y * VIEW_TAN_Y);
  double lx, ly, lz;
  do {
    lz = cmin + (1.0 - cmin) * dacpo_rng_uniform(r);
    const double phi = 2.0 * SCENE_PI * dacpo_rng_uniform(r);
    const double s = sqrt(fmax(0.0, 1.0 - lz * lz));
    lx = s * cos(phi);
    ly = s * sin(phi);
  } while (fabs(lx) > VIEW_TAN_X * lz || fabs(ly) > VIEW_TAN_Y * lz);
  for (int k = 0; k < 3; ++k)
    d[k] = lx * cam->right[k] + ly * cam->up[k] + lz * cam->fwd[k];
}

typedef struct raster_key {
  double u, v; /* image position, left to right and top to bottom, in [0, 1) */
  double key;  /* row, then u within it */
  size_t point;
} raster_key;

static int
cmp_raster_key(const void* a, const void* b)
{
  const double x = ((const raster_key*)a)->key, y = ((const raster_key*)b)->key;
  return (x > y) - (x < y);
}

/* The image position of ray d: u left to right, v top to bottom, in [0, 1). */
static void
image_position(const view_cam* cam, const double d[3], double* u, double* v)
{
  const double z = dot3(d, cam->fwd);
  *u = fmin(fmax((dot3(d, cam->right) / z + VIEW_TAN_X) / (2.0 * VIEW_TAN_X), 0.0),
            0.999999);
  *v = fmin(fmax((VIEW_TAN_Y - dot3(d, cam->up) / z) / (2.0 * VIEW_TAN_Y), 0.0),
            0.999999);
}

/* Points [first, first + count) of s put in raster order (a depth frame's
 * pixels come row by row): an image of about `rays` pixels, as wide for its
 * height as the field of view, its rows top to bottom, each left to right.
 * Returns 0, or -1 out of memory. */
static int
raster_order(raster_key* keys, size_t count, size_t rays, size_t first, dacpo_scene* s)
{
  const double rows = fmax(1.0, floor(sqrt((double)rays * VIEW_TAN_Y / VIEW_TAN_X)));
  for (size_t j = 0; j < count; ++j)
    keys[j].key = floor(keys[j].v * rows) + keys[j].u;
  float* xyz = malloc((count ? count : 1) * 6 * sizeof(float));
  int32_t* part = malloc((count ? count : 1) * sizeof(int32_t));
  if (!xyz || !part) {
    free(xyz);
    free(part);
    return -1;
  }
  qsort(keys, count, sizeof(raster_key), cmp_raster_key);
  for (size_t j = 0; j < count; ++j) {
    const size_t i = first + keys[j].point;
    memcpy(xyz + 6 * j, s->xyz + 3 * i, 3 * sizeof(float));
    memcpy(xyz + 6 * j + 3, s->normals + 3 * i, 3 * sizeof(float));
    part[j] = s->part[i];
  }
  for (size_t j = 0; j < count; ++j) {
    memcpy(s->xyz + 3 * (first + j), xyz + 6 * j, 3 * sizeof(float));
    memcpy(s->normals + 3 * (first + j), xyz + 6 * j + 3, 3 * sizeof(float));
    s->part[first + j] = part[j];
  }
  free(xyz);
  free(part);
  return 0;
}

/* count points seen by cam into s from index first, in raster order. Returns
 * 0, or -1 when the view sees too little (or out of memory). */
static int
sample_view(const scene_builder* b, const view_cam* cam, size_t count, size_t first, dacpo_rng* r, dacpo_scene* s)
{
  const size_t max_rays = 400 * count + 100000;
  raster_key* keys = malloc((count ? count : 1) * sizeof(raster_key));
  if (!keys)
    return -1;
  size_t got = 0;
  size_t rays = 0;
  for (; got < count && rays < max_rays; ++rays) {
    double d[3], x[3], n[3], t;
    draw_ray(cam, r, d);
    const int h = nearest_hit(b, cam->eye, d, VIEW_FAR, &t);
    if (h < 0 || t < VIEW_NEAR)
      continue; /* nothing in range: no depth for this pixel */
    for (int k = 0; k < 3; ++k)
      x[k] = cam->eye[k] + t * d[k];
    prim_normal(&b->prims[h], x, n);
    const double flip = dot3(n, d) > 0.0 ? -1.0 : 1.0; /* towards the camera */
    image_position(cam, d, &keys[got].u, &keys[got].v);
    keys[got].point = got;
    const size_t i = first + got++;
    const double rel[3] = {x[0] - cam->eye[0], x[1] - cam->eye[1], x[2] - cam->eye[2]};
    for (int k = 0; k < 3; ++k) {
      const double* R = cam->rot + 3 * k;
      s->xyz[3 * i + k] = (float)(cam->eye[k] + dot3(R, rel) + cam->move[k]);
      s->normals[3 * i + k] = (float)(flip * dot3(R, n));
    }
    s->part[i] = (int32_t)h;
  }
  const int ok = got == count && raster_order(keys, count, rays, first, s) == 0;
  free(keys);
  return ok ? 0 : -1;
}

int
dacpo_scene_sample_views(const scene_builder* b,
                         const dacpo_scene_params* params,
                         dacpo_scene* s,
                         dacpo_scene_view_info* info,
                         char* err,
                         size_t errlen)
{
  static view_ctx zero_ctx;
  view_ctx cx = zero_ctx;
  dacpo_rng r;
  const unsigned views = params->views;
  const size_t n = params->target_points;
  size_t next = 0;
  dacpo_rng_seed(&r, params->seed, STREAM_VIEWS);
  init_ctx(&cx, b, &r);
  info->views = views;
  for (unsigned v = 0; v < views; ++v) {
    view_cam cam;
    const size_t count = n / views + (v < n % views ? 1 : 0);
    if (make_camera(&cx, params, v, &r, &cam) != 0) {
      dacpo_support_err(err, errlen, "view %u: no free camera place found", v);
      return -1;
    }
    memcpy(info->eye[v], cam.eye, sizeof(cam.eye));
    memcpy(info->target[v], cam.target, sizeof(cam.target));
    info->view_start[v] = next;
    if (sample_view(b, &cam, count, next, &r, s) != 0) {
      dacpo_support_err(err, errlen, "view %u sees too little of the scene", v);
      return -1;
    }
    next += count;
  }
  info->view_start[views] = next;
  s->n = next;
  return 0;
}
