/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * dacpo_make_scene: write a synthetic scene with ground-truth normals as binary
 * little-endian PLY (float x y z nx ny nz). Plain C, needs only dacpo_support.
 *
 *   dacpo_make_scene out.ply [-scene room] [-n 100000] [-noise 0] [-downsample 0]
 *                            [-fused V,SHIFT,DEG] [-views V,SHIFT,DEG] [-seed 1]
 *                            [-offset X,Y,Z] [-scale S]
 *
 * -offset moves the scene and -scale scales it (x S, then + offset); both write
 * double x y z (georeferenced scans: in float, an offset of 5e6 m leaves a
 * 0.5 m grid; 1e22 or 1e-23 m scenes test the range of the search).
 *
 * Exit status: 0 on success, 1 for bad arguments, 2 when generation or writing
 * fails.
 */
#include "dacpo_pcd.h"
#include "dacpo_ply.h"
#include "dacpo_scene.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Binary little-endian PLY with double x y z (x scale + offset) and float
 * normals. */
static int
write_ply_offset(const char* path,
                 const dacpo_scene* sc,
                 double scale,
                 const double off[3],
                 const char* tag)
{
  FILE* f = fopen(path, "wb");
  if (!f)
    return -1;
  fprintf(f,
          "ply\nformat binary_little_endian 1.0\ncomment %s\nelement vertex %zu\n"
          "property double x\nproperty double y\nproperty double z\n"
          "property float nx\nproperty float ny\nproperty float nz\nend_header\n",
          tag,
          sc->n);
  for (size_t i = 0; i < sc->n; ++i) {
    double p[3];
    for (int d = 0; d < 3; ++d)
      p[d] = scale * (double)sc->xyz[3 * i + d] + off[d];
    if (fwrite(p, sizeof(double), 3, f) != 3 ||
        fwrite(sc->normals + 3 * i, sizeof(float), 3, f) != 3)
      break;
  }
  const int bad = ferror(f);
  return fclose(f) != 0 || bad ? -1 : 0;
}

static void
print_help(const char* prog)
{
  dacpo_scene_params d;
  dacpo_scene_params_init(&d);
  printf("Write a synthetic scene with ground-truth normals as binary PLY or PCD "
         "by the output's\nextension (float x y z nx ny nz).\n\n");
  printf("Usage: %s out.ply|out.pcd <options>\n\nOptions:\n", prog);
  printf("  -scene NAME      scene kind (default: %s); one of:\n",
         dacpo_scene_kind_name(d.kind));
  printf("                     ");
  for (unsigned k = 0; k < DACPO_SCENE_KIND_COUNT; ++k)
    printf("%s%s",
           dacpo_scene_kind_name(k),
           k + 1 < DACPO_SCENE_KIND_COUNT ? " | " : "\n");
  printf("  -n N             points sampled before downsampling (default: %zu)\n",
         d.target_points);
  printf("  -noise SIGMA     Gaussian displacement sigma in metres along a random\n"
         "                   direction, e.g. 0.004 or 0.008 (default: %g)\n",
         d.noise_sigma);
  printf(
      "  -downsample M    keep a random subset of M points, 0 = all (default: %zu)\n",
      d.downsample_to);
  printf("  -fused V,SHIFT,DEG  fuse V views with a registration error: each point\n"
         "                   belongs to one at random, each view but the first moved\n"
         "                   by SHIFT metres and turned by DEG degrees (random\n"
         "                   directions), so surfaces come as offset copies, e.g.\n"
         "                   3,0.008,0.2 (default: none)\n");
  printf(
      "  -views V,SHIFT,DEG  V depth-camera views (60x45 deg, 0.3-6 m) like "
      "registered\n"
      "                   RGB-D frames concatenated: each camera keeps the surface it\n"
      "                   sees unoccluded (density ~ cos/range^2), view by view and\n"
      "                   each view row by row as a depth image's pixels, each\n"
      "                   view but the first moved by SHIFT metres and turned by DEG\n"
      "                   degrees about its camera (random directions); normals face\n"
      "                   their camera, e.g. 20,0.02,0.5 (V <= %d; default: none)\n",
      DACPO_SCENE_MAX_VIEWS);
  printf("  -seed S          random seed (default: %llu)\n",
         (unsigned long long)d.seed);
  printf("  -offset X,Y,Z    add this offset and write double x y z (as georeferenced\n"
         "                   scans do), e.g. 4.5e5,5.4e6,120 (default: none, float)\n");
  printf("  -scale S         multiply the coordinates by S (before -offset) and write\n"
         "                   double x y z (default: none)\n");
  printf("  -h, --help       this text\n\n");
  printf("Example: %s room.ply -scene room -n 200000 -noise 0.004\n", prog);
}

/* Strict parsers: the whole argument must be a number in range. */
static int
parse_u64(const char* s, uint64_t* out)
{
  char* end;
  unsigned long long u;
  if (!s || *s < '0' || *s > '9')
    return -1;
  errno = 0;
  u = strtoull(s, &end, 10);
  if (errno != 0 || *end != '\0')
    return -1;
  *out = (uint64_t)u;
  return 0;
}

static int
parse_size(const char* s, size_t* out)
{
  uint64_t v;
  if (parse_u64(s, &v) != 0 || v > (uint64_t)SIZE_MAX)
    return -1;
  *out = (size_t)v;
  return 0;
}

static int
parse_nonneg_double(const char* s, double* out)
{
  char* end;
  double v;
  if (!s || *s == '\0')
    return -1;
  errno = 0;
  v = strtod(s, &end);
  if (errno != 0 || *end != '\0' || !isfinite(v) || v < 0.0)
    return -1;
  *out = v;
  return 0;
}

static double
now_seconds(void)
{
  struct timespec ts;
  if (timespec_get(&ts, TIME_UTC) != TIME_UTC)
    return 0.0;
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int
usage_error(const char* prog, const char* msg, const char* arg)
{
  fprintf(stderr, "%s: %s%s%s\n", prog, msg, arg ? " " : "", arg ? arg : "");
  fprintf(stderr, "Run '%s -h' for usage.\n", prog);
  return 1;
}

/* What the command line asks for. */
typedef struct make_options {
  const char* out_path;
  double offset[3], scale;
  int use_offset; /* -offset or -scale: write double x y z */
  dacpo_scene_params p;
} make_options;

/* Option a with its value v (NULL if a is last). Returns 0, or the exit
 * status after a usage error. */
static int
apply_option(const char* prog, const char* a, const char* v, make_options* o)
{
  dacpo_scene_params* p = &o->p;
  if (strcmp(a, "-scene") && strcmp(a, "-n") && strcmp(a, "-noise") &&
      strcmp(a, "-downsample") && strcmp(a, "-seed") && strcmp(a, "-offset") &&
      strcmp(a, "-scale") && strcmp(a, "-fused") && strcmp(a, "-views"))
    return usage_error(prog, "unknown option", a);
  if (!v)
    return usage_error(prog, "missing value after", a);
  if (strcmp(a, "-scene") == 0) {
    if (dacpo_scene_kind_from_name(v, &p->kind) != 0)
      return usage_error(prog, "unknown scene", v);
  }
  else if (strcmp(a, "-n") == 0) {
    if (parse_size(v, &p->target_points) != 0 || p->target_points == 0)
      return usage_error(prog, "-n needs a positive integer, got", v);
  }
  else if (strcmp(a, "-noise") == 0) {
    if (parse_nonneg_double(v, &p->noise_sigma) != 0)
      return usage_error(prog, "-noise needs a finite number >= 0, got", v);
  }
  else if (strcmp(a, "-downsample") == 0) {
    if (parse_size(v, &p->downsample_to) != 0)
      return usage_error(prog, "-downsample needs an integer >= 0, got", v);
  }
  else if (strcmp(a, "-seed") == 0) {
    if (parse_u64(v, &p->seed) != 0)
      return usage_error(prog, "-seed needs an integer >= 0, got", v);
  }
  else if (strcmp(a, "-fused") == 0) {
    char tail = 0;
    if (sscanf(v, "%u,%lf,%lf%c", &p->fused_views, &p->fused_shift, &p->fused_angle, &tail) !=
            3 ||
        p->fused_views > DACPO_SCENE_MAX_FUSED_VIEWS || !isfinite(p->fused_shift) ||
        !(p->fused_shift >= 0.0) || !isfinite(p->fused_angle) || !(p->fused_angle >= 0.0))
      return usage_error(
          prog, "-fused needs V,SHIFT,DEG (V <= 16, SHIFT and DEG finite >= 0), got", v);
  }
  else if (strcmp(a, "-views") == 0) {
    char tail = 0;
    if (sscanf(v, "%u,%lf,%lf%c", &p->views, &p->view_shift, &p->view_angle, &tail) != 3 ||
        p->views < 1 || p->views > DACPO_SCENE_MAX_VIEWS || !isfinite(p->view_shift) ||
        !(p->view_shift >= 0.0) || !isfinite(p->view_angle) || !(p->view_angle >= 0.0))
      return usage_error(
          prog, "-views needs V,SHIFT,DEG (1 <= V <= 64, SHIFT and DEG finite >= 0), got", v);
  }
  else if (strcmp(a, "-offset") == 0) {
    char tail = 0;
    double* off = o->offset;
    if (sscanf(v, "%lf,%lf,%lf%c", &off[0], &off[1], &off[2], &tail) != 3 ||
        !isfinite(off[0]) || !isfinite(off[1]) || !isfinite(off[2]))
      return usage_error(prog, "-offset needs three finite numbers X,Y,Z, got", v);
    o->use_offset = 1;
  }
  else if (strcmp(a, "-scale") == 0) {
    char* end = NULL;
    o->scale = strtod(v, &end);
    if (end == v || *end != '\0' || !isfinite(o->scale) || !(o->scale > 0.0))
      return usage_error(prog, "-scale needs a finite number > 0, got", v);
    o->use_offset = 1;
  }
  return 0;
}

/* Reads the command line in order (help wins where it stands). Returns -1 to
 * go on, else the exit status. */
static int
parse_args(int argc, char** argv, const char* prog, make_options* o)
{
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : NULL;
    if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0 || strcmp(a, "-help") == 0) {
      print_help(prog);
      return 0;
    }
    if (a[0] == '-' && a[1] != '\0') {
      const int rc = apply_option(prog, a, v, o);
      if (rc != 0)
        return rc;
      ++i;
      continue;
    }
    if (o->out_path)
      return usage_error(prog, "more than one output file given:", a);
    o->out_path = a;
  }
  if (!o->out_path)
    return usage_error(prog, "no output file given", NULL);
  /* the format follows the name: a PLY under a .pcd name crashed PCL readers */
  const int ply = dacpo_is_ply_path(o->out_path);
  if (!ply && !dacpo_is_pcd_path(o->out_path))
    return usage_error(prog, "the output must end in .ply or .pcd:", o->out_path);
  if (!ply && o->use_offset)
    return usage_error(prog, "-offset / -scale write double x y z: use a .ply name, not",
                       o->out_path);
  if (o->p.views > 0 && o->p.fused_views > 1)
    return usage_error(prog, "-views and -fused exclude each other", NULL);
  if (o->p.downsample_to > o->p.target_points) {
    fprintf(stderr,
            "%s: -downsample %zu is larger than -n %zu\n",
            prog,
            o->p.downsample_to,
            o->p.target_points);
    return 1;
  }
  return -1;
}

/* Writes the scene: float PLY with the parameters as comment, or double x y z
 * with -offset / -scale. Returns 0, or 2 after a message. */
static int
write_scene(const char* prog, const make_options* o, const dacpo_scene* scene)
{
  const dacpo_scene_params* p = &o->p;
  char err[512] = ""; /* as left by a successful dacpo_scene_generate */
  char comment[512];
  snprintf(comment,
           sizeof(comment),
           "GT normals: analytic (dacpo_make_scene)\n"
           "scene %s n %zu noise %g downsample %zu seed %llu",
           dacpo_scene_kind_name(p->kind),
           p->target_points,
           p->noise_sigma,
           p->downsample_to,
           (unsigned long long)p->seed);
  if (o->use_offset ? write_ply_offset(o->out_path,
                                       scene,
                                       o->scale,
                                       o->offset,
                                       "moved (dacpo_make_scene -scale/-offset)") != 0
                    : dacpo_points_write(o->out_path,
                                      scene->xyz,
                                      scene->normals,
                                      scene->n,
                                      comment,
                                      err,
                                      sizeof(err)) != 0) {
    if (o->use_offset)
      snprintf(err, sizeof(err), "cannot write '%s': %s", o->out_path, strerror(errno));
    fprintf(stderr, "%s: %s\n", prog, err);
    return 2;
  }
  return 0;
}

int
main(int argc, char** argv)
{
  const char* prog = argc > 0 && argv[0] ? argv[0] : "dacpo_make_scene";
  make_options o;
  dacpo_scene scene;
  char err[512];
  double t0, t1, t2;

  memset(&o, 0, sizeof(o));
  o.scale = 1.0;
  dacpo_scene_params_init(&o.p);
  if (argc < 2) {
    print_help(prog);
    return 1;
  }
  const int rc = parse_args(argc, argv, prog, &o);
  if (rc >= 0)
    return rc;

  t0 = now_seconds();
  if (dacpo_scene_generate(&o.p, &scene, err, sizeof(err)) != 0) {
    fprintf(stderr, "%s: cannot generate the scene: %s\n", prog, err);
    return 2;
  }
  t1 = now_seconds();
  if (write_scene(prog, &o, &scene) != 0) {
    dacpo_scene_free(&scene);
    return 2;
  }
  t2 = now_seconds();
  printf("wrote %zu points (scene %s, %zu surface patches, noise %g, seed %llu) to %s "
         "[generate %.3f s, write %.3f s]\n",
         scene.n,
         dacpo_scene_kind_name(o.p.kind),
         scene.num_parts,
         o.p.noise_sigma,
         (unsigned long long)o.p.seed,
         o.out_path,
         t1 - t0,
         t2 - t1);
  dacpo_scene_free(&scene);
  return 0;
}
