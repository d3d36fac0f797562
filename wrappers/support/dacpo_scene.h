/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_scene.h
 * \brief Synthetic scenes with ground-truth normals, random sign scrambling and
 *        the paper's orientation score. Used by tests, samples, the demo and the
 *        benchmarks; pure C11, independent of the core's private headers.
 *
 * A scene is a list of analytic surface patches (rectangles with rectangular
 * holes, cylinder patches, annuli, spheres). Points are drawn uniformly by area,
 * the total is exactly `target_points`; ground-truth normals are unit vectors
 * pointing into free space (into the room for walls and floor, out of the solid
 * for both faces of thin objects). Optional Gaussian noise (paper section 6:
 * displacement sigma * N(0,1) along a uniformly random direction; normals keep
 * the ground truth) and optional random downsampling (order preserved).
 *
 * Everything is deterministic per seed and free of global state, so it can be
 * called from several threads at once. Nothing here prints, exits or aborts;
 * failures return non-zero and write a message to `err`.
 *
 * Coordinates are metres, z is up.
 */
#ifndef DACPO_SCENE_H
#define DACPO_SCENE_H

#include "dacpo_score.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** \brief Scene kinds (values are stable). */
typedef enum dacpo_scene_kind {
  /** Open ScanNet-like room, 6 x 5 x 2.6 m: floor and the inner faces of four walls
   *  (door opening in the y = 0 wall, no ceiling) with a table (4 cm top on four
   *  open-cylinder legs), two chairs (3 cm seats, 2 cm backrests, box legs), a
   *  bookshelf of 2 cm boards, a thick-walled open bin (both faces and rim), a
   *  free-standing 10 cm partition wall, a thin 2 cm screen on legs and a cabinet
   *  against a wall. The default scene. */
  DACPO_SCENE_ROOM = 0,
  /** 2 x 2 m square in z = 0, x, y in [-1, 1], normal +z. One part. */
  DACPO_SCENE_PLANE = 1,
  /** Closed unit sphere at the origin, normals outward. One part. */
  DACPO_SCENE_SPHERE = 2,
  /** Two 4 x 3 x 2.5 m open rooms side by side along x, joined by a door in a
   *  10 cm shared wall (x in [4, 4.1]); both faces of the shared wall, its top,
   *  the door's jambs and lintel and the floor strip under the door are sampled. */
  DACPO_SCENE_TWO_ROOMS = 3,
  /** Floating thin board 1.0 x 0.6 x 0.02 m centred at the origin, all six faces;
   *  parts 0..5 are the faces +x, -x, +y, -y, +z (top), -z (bottom). */
  DACPO_SCENE_BOARD = 4,
  /** Half cylinder: radius 1, axis y, y in [-1, 1], the z >= 0 half, normals
   *  outward. One part. */
  DACPO_SCENE_HALF_CYLINDER = 5,
  /** S-shaped sheet in the xz plane extruded along y (y in [-1, 1]): two half
   *  circles of radius 0.5 joined at (0, 1); part 0 lower arc, part 1 upper arc;
   *  normals consistent across the joint. */
  DACPO_SCENE_S_SHEET = 6,
  /** Open box room 4 x 3 x 2.5 m, x in [0, 4], y in [0, 3]: floor and the inner
   *  faces of four walls (5 parts), no ceiling. */
  DACPO_SCENE_BOX_OPEN = 7,
  /** Thin-structure known answers (z up, normals out of the solids, into the
   *  room for floor and walls). Table on a 2.4 x 2 m floor: 1.2 x 0.7 m top
   *  2 cm thick at 0.72 m (all faces), four 4 x 4 cm legs. */
  DACPO_SCENE_TABLE = 8,
  /** Free-standing open tube: outer radius 0.15 m, 2 cm wall, 0.5 m tall; outer
   *  and inner faces and both rims. */
  DACPO_SCENE_TUBE = 9,
  /** 2 cm partition (2 x 1.8 m, both faces, top, ends) standing on a 4 x 3 m
   *  floor midway between two walls that face each other. */
  DACPO_SCENE_PARTITION = 10,
  /** One floor of a building, 12.4 x 9.2 m: a 2 m corridor along x between
   *  three 4 x 3.5 m rooms on each side, 10 cm walls 2.6 m high, no ceiling;
   *  a 0.9 x 2 m door from every room to the corridor. Both faces of the inner
   *  walls, their tops, the door jambs, lintels and floor strips are sampled;
   *  the outer walls only from inside. For scale-out runs. */
  DACPO_SCENE_BUILDING = 11,
  DACPO_SCENE_KIND_COUNT = 12
} dacpo_scene_kind;

/** \brief Room scene dimensions (DACPO_SCENE_ROOM), metres. */
#define DACPO_SCENE_ROOM_SIZE_X 6.0
#define DACPO_SCENE_ROOM_SIZE_Y 5.0
#define DACPO_SCENE_ROOM_HEIGHT 2.6

/** \brief Most views dacpo_scene_params::fused_views takes. */
#define DACPO_SCENE_MAX_FUSED_VIEWS 16

/** \brief Most depth-camera views dacpo_scene_params::views takes. */
#define DACPO_SCENE_MAX_VIEWS 64

/** \brief Generation parameters; fill with dacpo_scene_params_init() first. */
typedef struct dacpo_scene_params {
  unsigned kind;        /**< a ::dacpo_scene_kind; default DACPO_SCENE_ROOM */
  size_t target_points; /**< points sampled before downsampling; default 100000 */
  double noise_sigma;   /**< Gaussian displacement sigma in metres (paper: 0.004,
                             0.008); default 0 = no noise */
  size_t downsample_to; /**< keep a random subset of this many points (order
                             preserved); 0 = keep all; default 0 */
  uint64_t seed;        /**< default 1 */
  unsigned fused_views; /**< views fused with a registration error: every point
                             belongs to one of them at random, and each view but
                             the first is moved by its own rigid error (below),
                             so every surface comes as offset copies; 0 or 1 =
                             none; default 0 */
  double fused_shift;   /**< the error's translation, metres (each view: this
                             length in a random direction); default 0.01 */
  double fused_angle;   /**< the error's rotation about the scene's centre,
                             degrees (random axis); default 0.2 */
  unsigned views;       /**< depth-camera views (like registered RGB-D frames
                             concatenated): each of `views` cameras (60 x 45
                             degrees, 0.3..6 m) keeps only the surface it sees,
                             unoccluded, with a density falling as cos/r^2; the
                             points come view by view, each view row by row
                             (its image's rows top to bottom, each left to
                             right, as a depth frame's pixels), each view's
                             share of target_points, and each view but the first is
                             moved by its own pose error (below); normals face
                             their own camera; 0 = none (uniform sampling);
                             not with fused_views > 1; default 0 */
  double view_shift;    /**< pose error translation, metres (random direction);
                             default 0.01 */
  double view_angle;    /**< pose error rotation about a random axis through the
                             camera, degrees; default 0.2 */
} dacpo_scene_params;

/** \brief The cameras of a scene generated with views (see
 *  dacpo_scene_generate_views). */
typedef struct dacpo_scene_view_info {
  unsigned views;   /**< number of views (0 when the scene has none) */
  size_t view_start[DACPO_SCENE_MAX_VIEWS + 1]; /**< view v's points are
                             [view_start[v], view_start[v + 1]) */
  double eye[DACPO_SCENE_MAX_VIEWS][3];    /**< camera centre (no pose error) */
  double target[DACPO_SCENE_MAX_VIEWS][3]; /**< the point it looks at */
} dacpo_scene_view_info;

/** \brief A generated scene. All arrays are owned; free with dacpo_scene_free(). */
typedef struct dacpo_scene {
  size_t n;             /**< number of points */
  float* xyz;           /**< 3n coordinates */
  float* normals;       /**< 3n unit ground-truth normals, pointing into free space */
  int32_t* part;        /**< n surface-patch ids in [0, num_parts) */
  size_t num_parts;     /**< number of surface patches */
  int32_t* part_object; /**< num_parts object ids in [0, num_objects) */
  size_t num_objects;   /**< number of objects (floor, wall, table, ...) */
  const char** object_name; /**< num_objects names (static strings, array owned) */
} dacpo_scene;

/** \brief Name of a scene kind ("room", "plane", ...), or NULL when out of range. */
const char*
dacpo_scene_kind_name(unsigned kind);

/** \brief Scene kind from its name; returns 0 and sets *kind, or -1 if unknown. */
int
dacpo_scene_kind_from_name(const char* name, unsigned* kind);

/** \brief Set the documented defaults. NULL-safe. */
void
dacpo_scene_params_init(dacpo_scene_params* params);

/**
 * \brief Generate a scene.
 * \param[in]  params  parameters (see dacpo_scene_params)
 * \param[out] out     the scene; zeroed first, left empty on failure
 * \param[out] err     message buffer (may be NULL)
 * \param[in]  errlen  size of err
 * \return 0 on success; -1 for invalid arguments (NULL pointer, unknown kind,
 *         target_points == 0, negative or non-finite noise, downsample_to >
 *         target_points, negative or non-finite fused_shift / fused_angle /
 *         view_shift / view_angle, views > DACPO_SCENE_MAX_VIEWS, views with
 *         fused_views > 1, or no camera place found), -2 when out of memory.
 * Cost: O(target_points) time and memory (28 bytes per point); with views,
 *       O(target_points * patches) ray casts.
 */
int
dacpo_scene_generate(const dacpo_scene_params* params,
                     dacpo_scene* out,
                     char* err,
                     size_t errlen);

/** \brief dacpo_scene_generate() that also reports the cameras (when
 *  params->views > 0) in \a info (may be NULL; zeroed first). view_start
 *  follows downsampling. */
int
dacpo_scene_generate_views(const dacpo_scene_params* params,
                           dacpo_scene* out,
                           dacpo_scene_view_info* info,
                           char* err,
                           size_t errlen);

/** \brief Free the arrays and zero the struct. NULL-safe, idempotent. */
void
dacpo_scene_free(dacpo_scene* scene);

/** \brief dacpo_scramble_signs() applied to the scene's ground-truth normals. */
size_t
dacpo_scene_scramble_signs(const dacpo_scene* scene,
                           float* normals_out,
                           uint64_t seed,
                           double fraction);

/**
 * \brief Two square sheets of side \a size, \a gap apart along z and facing away
 * from each other (lower -z, upper +z): a thin board without its rim. Points on
 * a jittered grid of \a spacing, moved by Gaussian noise of \a sigma along
 * random directions. Returns 0, or -1 with a message.
 */
int
dacpo_scene_parallel_sheets(double size,
                            double spacing,
                            double gap,
                            double sigma,
                            uint64_t seed,
                            dacpo_scene* out,
                            char* err,
                            size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* DACPO_SCENE_H */
