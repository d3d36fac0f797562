// SPDX-License-Identifier: BSD-3-Clause
// pcl_dacpo._core: the C API for Python (pybind11 + numpy). The public,
// keyword-checked API lives in pcl_dacpo/__init__.py; this layer only moves
// arrays in and out, fills dacpo_params from a dict of already-named fields,
// releases the GIL while the core runs and turns Ctrl-C or a progress callback
// returning False into a clean cancel.
#include <dacpo/dacpo.h>
#include <dacpo/dacpo_param_table.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

extern "C" {
#include "dacpo_scene.h"
}

namespace py = pybind11;

namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

/* The table's rows Python sees as keywords: all but the two the package sets
 * itself (estimate_normals: from the normals argument; keep_mesh: no mesh
 * out of Python). */
bool
pythonKeyword(const char* name)
{
  return std::strcmp(name, "estimate_normals") != 0 &&
         std::strcmp(name, "keep_mesh") != 0;
}

/* A field as Python sees it, by the table's kind. */
py::object
toPySIZE(size_t v)
{
  return py::int_(v);
}
py::object
toPyREAL(double v)
{
  return py::float_(v);
}
py::object
toPyFLAG(int v)
{
  return py::bool_(v != 0);
}
py::object
toPyINT(int v)
{
  return py::int_(v);
}
template <typename E>
py::object
toPyENUM(E v)
{
  return py::int_(static_cast<int>(v));
}
py::object
toPyU64(uint64_t v)
{
  return py::int_(v);
}
py::object
toPyUINT(unsigned v)
{
  return py::int_(v);
}

/* Every keyword with its C default (dacpo_param_table.h), for Python's checks. */
py::dict
defaultParams()
{
  dacpo_params p;
  dacpo_params_init(&p);
  py::dict d;
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc)                                              \
  if (pythonKeyword(#name))                                                            \
    d[#name] = toPy##kind(p.name);
  DACPO_PARAMS()
#undef DACPO_PARAM
  d["viewpoint"] = py::make_tuple(p.viewpoint[0], p.viewpoint[1], p.viewpoint[2]);
  return d;
}

/* A keyword's value as T; a value T cannot hold (k=2**70, seed=-1, k="x")
 * is a ValueError naming the keyword, not pybind11's "Unable to cast". */
template <typename T>
T
get(const py::dict& d, const char* name, T fallback)
{
  if (!d.contains(name))
    return fallback;
  try {
    return d[name].cast<T>();
  } catch (const py::cast_error&) {
    throw py::value_error(
        std::string(name) + "=" + py::repr(d[name]).cast<std::string>() +
        ": not a value this keyword can take (see help(pcl_dacpo.orient))");
  }
}

/* A keyword's value into a field, by the table's kind (the field keeps its
 * value when the keyword is absent). */
void
fromPySIZE(const py::dict& d, const char* n, size_t& f)
{
  f = get<size_t>(d, n, f);
}
void
fromPyREAL(const py::dict& d, const char* n, double& f)
{
  f = get<double>(d, n, f);
}
void
fromPyFLAG(const py::dict& d, const char* n, int& f)
{
  f = get<bool>(d, n, f != 0) ? 1 : 0;
}
void
fromPyINT(const py::dict& d, const char* n, int& f)
{
  f = get<int>(d, n, f);
}
template <typename E>
void
fromPyENUM(const py::dict& d, const char* n, E& f)
{
  f = static_cast<E>(get<int>(d, n, static_cast<int>(f)));
}
void
fromPyU64(const py::dict& d, const char* n, uint64_t& f)
{
  f = get<uint64_t>(d, n, f);
}
void
fromPyUINT(const py::dict& d, const char* n, unsigned& f)
{
  f = get<unsigned>(d, n, f);
}

dacpo_params
toParams(const py::dict& d)
{
  dacpo_params p;
  dacpo_params_init(&p);
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc)                                              \
  if (pythonKeyword(#name))                                                            \
    fromPy##kind(d, #name, p.name);
  DACPO_PARAMS()
#undef DACPO_PARAM
  if (d.contains("viewpoint")) {
    const py::tuple v = py::tuple(d["viewpoint"]);
    for (int i = 0; i < 3; ++i)
      p.viewpoint[i] = v[i].cast<double>();
  }
  p.estimate_normals = get<bool>(d, "estimate_normals", false) ? 1 : 0;
  return p;
}

/* "" or the message naming the bad field. */
std::string
validate(const py::dict& d)
{
  const dacpo_params p = toParams(d);
  char msg[256] = "";
  return dacpo_params_validate(&p, msg, sizeof(msg)) == DACPO_OK ? std::string() : msg;
}

struct ProgressState {
  py::object callback; /* None or callable(stage_name, fraction) -> bool */
  bool cancelled_by_user = false;
  bool interrupted = false;
  py::error_already_set* error = nullptr;
};

/* Called by the core on the calling thread with the GIL released. */
int
progressHook(void* user, dacpo_stage stage, double fraction)
{
  auto* st = static_cast<ProgressState*>(user);
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) { /* Ctrl-C: KeyboardInterrupt is pending */
    st->interrupted = true;
    return 1;
  }
  if (st->callback.is_none())
    return 0;
  try {
    const py::object r = st->callback(dacpo_stage_name(stage), fraction);
    if (!r.is_none() && !r.cast<bool>()) {
      st->cancelled_by_user = true;
      return 1;
    }
  } catch (py::error_already_set& e) {
    st->error = new py::error_already_set(std::move(e));
    return 1;
  }
  return 0;
}

struct CtxDeleter {
  void
  operator()(dacpo_ctx* c) const
  {
    dacpo_ctx_free(c);
  }
};

/* The starting normals into out (3n): the given ones, or zeros with
 * estimate_normals set when normals_in is None. */
void
startNormals(const FloatArray& points,
             py::object normals_in,
             dacpo_params& p,
             float* out)
{
  const size_t n = static_cast<size_t>(points.shape(0));
  if (normals_in.is_none()) {
    p.estimate_normals = 1;
    std::memset(out, 0, 3 * n * sizeof(float));
    return;
  }
  FloatArray given = normals_in.cast<FloatArray>();
  if (given.ndim() != 2 || given.shape(0) != points.shape(0) || given.shape(1) != 3)
    throw py::value_error("normals must have the shape of points, (N, 3)");
  std::memcpy(out, given.data(), 3 * n * sizeof(float));
}

/* The run's stats as a dict (stage times by stage name). */
py::dict
statsDict(const dacpo_stats* s)
{
  py::dict stats;
  stats["input_points"] = s->input_points;
  stats["unique_points"] = s->unique_points;
  stats["duplicate_points"] = s->duplicate_points;
  stats["k_used"] = s->k_used;
  stats["num_components"] = s->num_components;
  stats["num_blocks"] = s->num_blocks;
  stats["num_block_edges"] = s->num_block_edges;
  stats["flipped_blocks"] = s->flipped_blocks;
  stats["solver_optimal"] = s->solver_optimal != 0;
  stats["num_parts"] = s->num_parts;
  stats["parts_related"] = s->parts_related;
  stats["cue_anchored_blocks"] = s->cue_anchored_blocks;
  stats["parts_cue_signed"] = s->parts_cue_signed;
  stats["surface_vote_turned"] = s->surface_vote_turned;
  stats["sensor_turned"] = s->sensor_turned;
  stats["frame_sensors"] = s->frame_sensors;
  stats["frame_turned"] = s->frame_turned;
  stats["cue_reconciled_blocks"] = s->cue_reconciled_blocks;
  stats["view_score"] = s->view_score;
  stats["sign_flipped"] = s->sign_flipped != 0;
  stats["sign_facing"] = s->sign_facing;
  stats["sign_enclosed"] = s->sign_enclosed != 0;
  stats["scan_kind"] =
      s->scan_kind == DACPO_SCAN_SINGLE_VIEW ? "single_view" : "multi_view";
  stats["single_view_fit"] = s->single_view_fit;
  stats["layered_share"] = s->layered_share;
  stats["layered_copies"] = s->layered_copies;
  stats["layered_doubled"] = s->layered_doubled;
  stats["layered_crossing"] = s->layered_crossing;
  stats["copy_scale_axes"] = s->copy_scale_axes;
  stats["dipole_sides_used"] = s->dipole_sides_used;
  stats["dipole_c_used"] = s->dipole_c_used;
  stats["dipole_layers_used"] = s->dipole_layers_used;
  stats["dipole_two_sheet_used"] = s->dipole_two_sheet_used;
  stats["total_seconds"] = s->total_seconds;
  stats["ipsr_iterations_total"] = s->ipsr_iterations_total;
  stats["ipsr_iterations_max"] = s->ipsr_iterations_max;
  stats["dipole_restarts_total"] = s->dipole_restarts_total;
  stats["dipole_blocks_all_restarts"] = s->dipole_blocks_all_restarts;
  stats["ipsr_cg_iterations_total"] = s->ipsr_cg_iterations_total;
  stats["ipsr_faces_total"] = s->ipsr_faces_total;
  stats["ipsr_surfaces_reused"] = s->ipsr_surfaces_reused;
  py::dict stage_seconds;
  for (int i = 0; i < DACPO_STAGE_COUNT; ++i)
    stage_seconds[dacpo_stage_name(static_cast<dacpo_stage>(i))] = s->stage_seconds[i];
  stats["stage_seconds"] = stage_seconds;
  return stats;
}

/* Per-point labels and confidence, per-block flips into r (zeros where the
 * run kept none). */
void
addLabelArrays(const dacpo_ctx* ctx, const dacpo_stats* s, py::dict& r)
{
  const size_t m = s->input_points;
  auto copy_i32 = [&](const int32_t* src) {
    py::array_t<int32_t> a(static_cast<py::ssize_t>(m));
    if (src)
      std::memcpy(a.mutable_data(), src, m * sizeof(int32_t));
    return a;
  };
  r["component_labels"] = copy_i32(dacpo_ctx_point_components(ctx));
  r["block_labels"] = copy_i32(dacpo_ctx_point_blocks(ctx));
  py::array_t<float> conf(static_cast<py::ssize_t>(m));
  if (const float* c = dacpo_ctx_point_confidence(ctx))
    std::memcpy(conf.mutable_data(), c, m * sizeof(float));
  r["confidence"] = conf;
  py::array_t<uint8_t> flips(static_cast<py::ssize_t>(s->num_blocks));
  if (const uint8_t* f = dacpo_ctx_block_flips(ctx))
    std::memcpy(flips.mutable_data(), f, s->num_blocks);
  r["block_flips"] = flips;
}

/* Returns a dict: status, message, and on success the arrays and stats. */
py::dict
orient(FloatArray points,
       py::object normals_in,
       const py::dict& params,
       py::object progress)
{
  if (points.ndim() != 2 || points.shape(1) != 3)
    throw py::value_error("points must have shape (N, 3)");
  const size_t n = static_cast<size_t>(points.shape(0));
  dacpo_params p = toParams(params);
  py::array_t<float> normals(
      {static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(3)});
  float* out = normals.mutable_data();
  startNormals(points, normals_in, p, out);

  dacpo_ctx* raw = nullptr;
  if (dacpo_ctx_create(&raw) != DACPO_OK)
    throw std::bad_alloc();
  std::unique_ptr<dacpo_ctx, CtxDeleter> ctx(raw);
  ProgressState state;
  state.callback = progress;
  dacpo_progress hook{&progressHook, &state};
  dacpo_status status;
  {
    py::gil_scoped_release release;
    status = dacpo_orient(ctx.get(), &p, nullptr, &hook, points.data(), out, n);
  }
  if (state.error) {
    py::error_already_set e = std::move(*state.error);
    delete state.error;
    throw e;
  }
  if (state.interrupted)
    throw py::error_already_set(); /* the pending KeyboardInterrupt */

  py::dict r;
  r["status"] = static_cast<int>(status);
  r["status_name"] = dacpo_status_string(status);
  r["message"] = std::string(dacpo_ctx_last_error(ctx.get()));
  r["cancelled_by_callback"] = state.cancelled_by_user;
  if (status != DACPO_OK)
    return r;
  const dacpo_stats* s = dacpo_ctx_stats(ctx.get());
  r["stats"] = statsDict(s);
  r["normals"] = normals;
  addLabelArrays(ctx.get(), s, r);
  return r;
}

/* A generated scene with ground truth (wrappers/support/dacpo_scene.h). */
py::tuple
makeScene(const std::string& kind, size_t points, uint64_t seed, double noise)
{
  dacpo_scene_params sp;
  dacpo_scene_params_init(&sp);
  if (dacpo_scene_kind_from_name(kind.c_str(), &sp.kind) != 0)
    throw py::value_error("unknown scene kind '" + kind + "'");
  sp.target_points = points;
  sp.seed = seed;
  sp.noise_sigma = noise;
  dacpo_scene s;
  char err[256] = "";
  if (dacpo_scene_generate(&sp, &s, err, sizeof(err)) != 0)
    throw py::value_error(err);
  py::array_t<float> xyz({static_cast<py::ssize_t>(s.n), static_cast<py::ssize_t>(3)});
  py::array_t<float> nrm({static_cast<py::ssize_t>(s.n), static_cast<py::ssize_t>(3)});
  std::memcpy(xyz.mutable_data(), s.xyz, 3 * s.n * sizeof(float));
  std::memcpy(nrm.mutable_data(), s.normals, 3 * s.n * sizeof(float));
  dacpo_scene_free(&s);
  return py::make_tuple(xyz, nrm);
}

} // namespace

PYBIND11_MODULE(_core, m)
{
  m.doc() = "pcl_dacpo's C core (use the pcl_dacpo package, not this module)";
  m.def("default_params", &defaultParams);
  m.def("validate", &validate);
  m.def("orient",
        &orient,
        py::arg("points"),
        py::arg("normals"),
        py::arg("params"),
        py::arg("progress"));
  m.def("make_scene",
        &makeScene,
        py::arg("kind"),
        py::arg("points"),
        py::arg("seed"),
        py::arg("noise"));
  m.attr("version") = dacpo_version_string();
}
