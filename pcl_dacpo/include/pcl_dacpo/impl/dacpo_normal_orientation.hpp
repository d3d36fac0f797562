/* SPDX-License-Identifier: BSD-3-Clause */
/* pcl::DACPONormalOrientation: packs the finite points of indices_, adapts the PCL
 * search to the core's dacpo_knn_fn, runs dacpo_orient() and copies the results
 * back in output order. Nothing thrown here may cross into the C core: the
 * callbacks catch everything and turn it into a non-zero return. */
#pragma once

#include <dacpo/dacpo.h>

#include <pcl_dacpo/dacpo_normal_orientation.h>

#include <pcl/common/copy_point.h>
#include <pcl/common/point_tests.h>
#include <pcl/console/print.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <utility>

namespace pcl {
namespace dacpo_detail {

/** Deleter so a std::unique_ptr owns a dacpo_ctx. */
struct ContextDeleter {
  void
  operator()(dacpo_ctx* ctx) const
  {
    dacpo_ctx_free(ctx);
  }
};
using ContextPtr = std::unique_ptr<dacpo_ctx, ContextDeleter>;

/** Remembers the first exception text raised inside a callback (any thread). */
class CallbackError {
public:
  void
  set(const std::string& message) noexcept
  {
    try {
      std::lock_guard<std::mutex> lock(mutex_);
      if (message_.empty())
        message_ = message;
    } catch (...) {
    }
  }
  std::string
  get() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return message_;
  }

private:
  mutable std::mutex mutex_;
  std::string message_;
};

/**
 * The core's neighbour callback over a pcl::search::Search. The core numbers
 * the packed points 0..m-1 ("local"); the search answers with indices into the
 * cloud. Neighbours outside the packed set (points not in indices_, or skipped as
 * non-finite) are dropped, and the search is asked again with a larger k until k
 * local neighbours are found or the searched cloud is exhausted.
 */
template <typename PointT>
struct SearchAdapter {
  const pcl::search::Search<PointT>* search = nullptr;
  const pcl::PointCloud<PointT>* cloud = nullptr;
  const std::vector<pcl::index_t>* local_to_cloud = nullptr;
  const std::vector<std::int32_t>* cloud_to_local = nullptr;
  std::size_t searchable_points = 0; /* points the search may return */
  double density_ratio = 1.0;        /* searchable_points / packed points */
  CallbackError error;

  static int
  knn(void* user,
      std::size_t query,
      std::size_t k,
      std::int32_t* indices,
      float* sq_distances,
      std::size_t* found) noexcept
  {
    auto* self = static_cast<SearchAdapter*>(user);
    try {
      *found = 0;
      if (query >= self->local_to_cloud->size()) {
        self->error.set("neighbour query for a point outside the packed cloud");
        return 1;
      }
      if (k == 0)
        return 0;
      const PointT& q = (*self->cloud)[(*self->local_to_cloud)[query]];
      const std::size_t limit = std::max<std::size_t>(self->searchable_points, 1);
      /* Start from the expected number of searchable points around a local one,
       * so a sparse subset usually needs a single query. */
      double guess = std::ceil(static_cast<double>(k) * self->density_ratio);
      std::size_t kq = static_cast<std::size_t>(std::min<double>(guess, limit));
      kq = std::max<std::size_t>(std::min(k, limit), kq);

      pcl::Indices nn;
      std::vector<float> nd;
      std::vector<std::pair<float, pcl::index_t>> order;
      for (;;) {
        const int got = self->search->nearestKSearch(q, static_cast<int>(kq), nn, nd);
        if (got < 0) {
          self->error.set("the PCL search returned an error");
          return 1;
        }
        const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(got),
                                                    std::min(nn.size(), nd.size()));
        /* Unsorted searches (PCL's default KdTree(false)) may answer in heap
         * order; the core wants nearest first. */
        order.clear();
        for (std::size_t i = 0; i < n; ++i)
          order.emplace_back(nd[i], nn[i]);
        if (!std::is_sorted(order.begin(), order.end()))
          std::sort(order.begin(), order.end());
        std::size_t w = 0;
        for (const auto& entry : order) {
          const pcl::index_t c = entry.second;
          if (c < 0 || static_cast<std::size_t>(c) >= self->cloud_to_local->size())
            continue;
          const std::int32_t local = (*self->cloud_to_local)[c];
          if (local < 0)
            continue;
          indices[w] = local;
          sq_distances[w] = entry.first;
          if (++w == k)
            break;
        }
        *found = w;
        if (w >= k || n < kq || kq >= limit)
          return 0;
        kq = std::min(limit, kq * 2);
      }
    } catch (const std::exception& e) {
      self->error.set(std::string("exception in the PCL search: ") + e.what());
    } catch (...) {
      self->error.set("unknown exception in the PCL search");
    }
    return 1;
  }
};

/** The core's progress callback over a std::function returning false to cancel. */
template <typename Callback>
struct ProgressAdapter {
  const Callback* callback = nullptr;
  CallbackError error;

  static int
  call(void* user, dacpo_stage stage, double fraction) noexcept
  {
    auto* self = static_cast<ProgressAdapter*>(user);
    try {
      return (*self->callback)(stage, fraction) ? 0 : 1;
    } catch (const std::exception& e) {
      self->error.set(std::string("exception in the progress callback: ") + e.what());
    } catch (...) {
      self->error.set("unknown exception in the progress callback");
    }
    return 1;
  }
};

inline bool
finiteAxis(const float n[3])
{
  return std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]) &&
         (n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f);
}

} // namespace dacpo_detail

template <typename PointInT, typename PointOutT>
DACPONormalOrientation<PointInT, PointOutT>::DACPONormalOrientation()
{
  static_assert(pcl::traits::has_xyz_v<PointInT>, "PointInT needs x, y, z");
  static_assert(pcl::traits::has_normal_v<PointOutT>,
                "PointOutT needs normal_x, normal_y, normal_z");
  feature_name_ = "DACPONormalOrientation";
  dacpo_params_init(&params_);
  std::memset(&stats_, 0, sizeof(stats_));
  this->setKSearch(static_cast<int>(params_.k));
}

template <typename PointInT, typename PointOutT>
void
DACPONormalOrientation<PointInT, PointOutT>::fail(PointCloudOut& output,
                                                  dacpo_status status,
                                                  const std::string& message)
{
  last_status_ = status;
  last_error_ = message;
  PCL_ERROR("[pcl::%s::computeFeature] %s: %s\n",
            getClassName().c_str(),
            dacpo_status_string(status),
            message.c_str());
  output.width = output.height = 0;
  output.clear();
  clearLabels();
}

template <typename PointInT, typename PointOutT>
bool
DACPONormalOrientation<PointInT, PointOutT>::initCompute()
{
  last_status_ = DACPO_OK;
  last_error_.clear();
  std::memset(&stats_, 0, sizeof(stats_));
  /* the cases PCL rejects before computeFeature(), named here */
  std::string why;
  if (!input_)
    why = "no input cloud (setInputCloud)";
  else if (input_->empty())
    why = "the input cloud is empty";
  else if (search_radius_ != 0.0 && k_ != 0)
    why = "both a search radius and k are set; DACPO needs k only (setRadiusSearch(0))";
  if (!why.empty() || !Feature<PointInT, PointOutT>::initCompute()) {
    last_status_ =
        input_ && input_->empty() ? DACPO_ERR_EMPTY_INPUT : DACPO_ERR_INVALID_ARGUMENT;
    last_error_ = why.empty()
                      ? "PCL's Feature::initCompute() rejected the input or the "
                        "search parameters"
                      : why;
    return false;
  }
  return true;
}

template <typename PointInT, typename PointOutT>
bool
DACPONormalOrientation<PointInT, PointOutT>::checkSetup(PointCloudOut& output)
{
  if (k_ <= 0 || search_radius_ != 0.0) {
    fail(output,
         DACPO_ERR_INVALID_ARGUMENT,
         "DACPO needs a k-NN graph: set k with setKSearch() (radius search is not "
         "supported)");
    return false;
  }
  if (!fake_surface_ && surface_ != input_) {
    fail(output,
         DACPO_ERR_INVALID_ARGUMENT,
         "a search surface other than the input cloud is not supported");
    return false;
  }
  if (normals_holder_ && normals_size_ != input_->size()) {
    fail(output,
         DACPO_ERR_INVALID_ARGUMENT,
         "the input normals have " + std::to_string(normals_size_) +
             " points but the input cloud has " + std::to_string(input_->size()));
    return false;
  }

  return true;
}

template <typename PointInT, typename PointOutT>
void
DACPONormalOrientation<PointInT, PointOutT>::packPoints(PointCloudOut& output,
                                                        Packed& packed) const
{
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  /* Pack the usable points: finite coordinates and, when given, a finite
   * non-zero axis. Everything else gets NaN and makes the output not dense. */
  const std::size_t n_out = indices_->size();
  std::vector<pcl::index_t>& local_to_cloud = packed.local_to_cloud;
  std::vector<std::size_t>& local_to_out = packed.local_to_out;
  std::vector<float>& xyz = packed.xyz;
  std::vector<float>& nrm = packed.nrm;
  std::vector<float>& given_curvature = packed.given_curvature;
  local_to_cloud.reserve(n_out);
  local_to_out.reserve(n_out);
  xyz.reserve(3 * n_out);
  nrm.reserve(3 * n_out);
  std::size_t skipped = 0;
  for (std::size_t i = 0; i < n_out; ++i) {
    const pcl::index_t c = (*indices_)[i];
    const PointInT& p = (*input_)[c];
    PointOutT& o = output[i];
    pcl::copyPoint(p, o);
    o.normal_x = o.normal_y = o.normal_z = nan;
    if constexpr (pcl::traits::has_curvature_v<PointOutT>)
      o.curvature = nan;

    bool usable = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    float axis[3] = {0.0f, 0.0f, 0.0f};
    float curv = 0.0f;
    if (usable && normals_holder_) {
      normals_reader_(normals_holder_.get(), static_cast<std::size_t>(c), axis, &curv);
      usable = dacpo_detail::finiteAxis(axis);
    }
    if (!usable) {
      ++skipped;
      continue;
    }
    local_to_cloud.push_back(c);
    local_to_out.push_back(i);
    xyz.insert(xyz.end(), {p.x, p.y, p.z});
    nrm.insert(nrm.end(), {axis[0], axis[1], axis[2]});
    if (normals_holder_)
      given_curvature.push_back(curv);
  }
  output.is_dense = (skipped == 0);
}

template <typename PointInT, typename PointOutT>
void
DACPONormalOrientation<PointInT, PointOutT>::copyResults(PointCloudOut& output,
                                                         const dacpo_ctx* ctx,
                                                         const Packed& packed)
{
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  const std::size_t n_out = indices_->size();
  const std::size_t m = packed.local_to_cloud.size();
  const std::vector<std::size_t>& local_to_out = packed.local_to_out;
  const std::vector<float>& nrm = packed.nrm;
  const std::vector<float>& given_curvature = packed.given_curvature;
  const float* curvature = dacpo_ctx_point_curvature(ctx);
  const std::int32_t* components = dacpo_ctx_point_components(ctx);
  const std::int32_t* blocks = dacpo_ctx_point_blocks(ctx);
  const float* confidence = dacpo_ctx_point_confidence(ctx);
  component_labels_.assign(n_out, -1);
  point_confidence_.assign(n_out, nan);
  block_labels_.assign(n_out, -1);
  for (std::size_t j = 0; j < m; ++j) {
    PointOutT& o = output[local_to_out[j]];
    o.normal_x = nrm[3 * j];
    o.normal_y = nrm[3 * j + 1];
    o.normal_z = nrm[3 * j + 2];
    if constexpr (pcl::traits::has_curvature_v<PointOutT>) {
      if (!given_curvature.empty())
        o.curvature = given_curvature[j];
      else
        o.curvature = curvature ? curvature[j] : 0.0f;
    }
    if (components)
      component_labels_[local_to_out[j]] = components[j];
    if (blocks)
      block_labels_[local_to_out[j]] = blocks[j];
    if (confidence)
      point_confidence_[local_to_out[j]] = confidence[j];
  }
  if (const std::uint8_t* flips = dacpo_ctx_block_flips(ctx))
    block_flips_.assign(flips, flips + stats_.num_blocks);
  if (const dacpo_edge_info* edges = dacpo_ctx_edges(ctx))
    edges_.assign(edges, edges + stats_.num_block_edges);
  {
    const float* mv = nullptr;
    const std::int32_t* mt = nullptr;
    std::size_t nv = 0;
    const std::size_t nt = dacpo_ctx_mesh(ctx, &mv, &nv, &mt);
    if (nt > 0) {
      mesh_vertices_.assign(mv, mv + 3 * nv);
      mesh_triangles_.assign(mt, mt + 3 * nt);
    }
  }
}

template <typename PointInT, typename PointOutT>
void
DACPONormalOrientation<PointInT, PointOutT>::warnAboutRun(
    const dacpo_params& params) const
{
  if (stats_.num_components > 1 && stats_.bridges_added > 0)
    PCL_WARN("[pcl::%s::computeFeature] the neighbour graph has %zu connected "
             "components; %zu bridge edges (longest %g) joined them and the cloud was "
             "oriented as one.\n",
             getClassName().c_str(),
             stats_.num_components,
             stats_.bridges_added,
             stats_.longest_bridge);
  else if (stats_.num_components > 1 && stats_.num_parts > 0)
    PCL_WARN("[pcl::%s::computeFeature] the neighbour graph has %zu connected "
             "components (largest %zu points); the sign of %zu of %zu parts was set by "
             "the viewpoint they imply (%.0f%% of the points face it), the rest keep "
             "an undefined sign.\n",
             getClassName().c_str(),
             stats_.num_components,
             stats_.largest_component,
             stats_.parts_related,
             stats_.num_parts > 0 ? stats_.num_parts - 1 : 0,
             100.0 * stats_.view_score);
  else if (stats_.num_components > 1)
    PCL_WARN("[pcl::%s::computeFeature] the neighbour graph has %zu connected "
             "components (largest %zu points); each is oriented on its own, their "
             "relative sign is undefined.\n",
             getClassName().c_str(),
             stats_.num_components,
             stats_.largest_component);
  if (!stats_.solver_optimal && stats_.num_block_edges > 0)
    PCL_WARN("[pcl::%s::computeFeature] the 0-1 program hit its time limit (%g s); "
             "the best answer found is used, not proven optimal.\n",
             getClassName().c_str(),
             params.solver_time_limit);
}

template <typename PointInT, typename PointOutT>
void
DACPONormalOrientation<PointInT, PointOutT>::clearResults()
{
  last_status_ = DACPO_OK;
  last_error_.clear();
  std::memset(&stats_, 0, sizeof(stats_));
  clearLabels();
}

template <typename PointInT, typename PointOutT>
void
DACPONormalOrientation<PointInT, PointOutT>::clearLabels()
{
  component_labels_.clear();
  point_confidence_.clear();
  block_labels_.clear();
  block_flips_.clear();
  edges_.clear();
  mesh_vertices_.clear();
  mesh_triangles_.clear();
}

template <typename PointInT, typename PointOutT>
bool
DACPONormalOrientation<PointInT, PointOutT>::checkPacked(PointCloudOut& output,
                                                         const Packed& packed)
{
  const std::size_t n_out = indices_->size();
  const std::size_t m = packed.local_to_cloud.size();
  if (m == 0) {
    fail(output,
         DACPO_ERR_EMPTY_INPUT,
         "none of the " + std::to_string(n_out) +
             " points has finite coordinates (and a usable input normal)");
    return false;
  }
  if (m >= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    fail(output, DACPO_ERR_INVALID_ARGUMENT, "too many points for 32-bit indices");
    return false;
  }
  if (static_cast<std::size_t>(k_) >= m)
    PCL_WARN("[pcl::%s::computeFeature] k = %d is not smaller than the %zu usable "
             "points; it is clamped.\n",
             getClassName().c_str(),
             k_,
             m);
  return true;
}

template <typename PointInT, typename PointOutT>
bool
DACPONormalOrientation<PointInT, PointOutT>::orientPacked(PointCloudOut& output,
                                                          const dacpo_params& params,
                                                          Packed& packed)
{
  const std::vector<pcl::index_t>& local_to_cloud = packed.local_to_cloud;
  const std::size_t m = local_to_cloud.size();
  std::vector<std::int32_t> cloud_to_local(input_->size(), -1);
  for (std::size_t j = 0; j < m; ++j)
    cloud_to_local[local_to_cloud[j]] = static_cast<std::int32_t>(j);

  dacpo_detail::SearchAdapter<PointInT> adapter;
  adapter.search = tree_.get();
  adapter.cloud = input_.get();
  adapter.local_to_cloud = &local_to_cloud;
  adapter.cloud_to_local = &cloud_to_local;
  const auto tree_indices = tree_->getIndices();
  adapter.searchable_points = tree_indices ? tree_indices->size() : surface_->size();
  adapter.density_ratio =
      m > 0 ? std::max(1.0,
                       static_cast<double>(adapter.searchable_points) /
                           static_cast<double>(m))
            : 1.0;
  dacpo_search search;
  search.knn = &dacpo_detail::SearchAdapter<PointInT>::knn;
  search.user = &adapter;

  dacpo_detail::ProgressAdapter<ProgressCallback> progress_adapter;
  progress_adapter.callback = &progress_;
  dacpo_progress progress;
  progress.fn = &dacpo_detail::ProgressAdapter<ProgressCallback>::call;
  progress.user = &progress_adapter;

  dacpo_ctx* raw = nullptr;
  dacpo_status status = dacpo_ctx_create(&raw);
  dacpo_detail::ContextPtr ctx(raw);
  if (status != DACPO_OK) {
    fail(output, status, "could not create a DACPO context");
    return false;
  }
  status = dacpo_orient(ctx.get(),
                        &params,
                        &search,
                        progress_ ? &progress : nullptr,
                        packed.xyz.data(),
                        packed.nrm.data(),
                        m);
  if (const dacpo_stats* s = dacpo_ctx_stats(ctx.get()))
    stats_ = *s;
  if (status != DACPO_OK) {
    std::string message = dacpo_ctx_last_error(ctx.get());
    const std::string search_error = adapter.error.get();
    const std::string progress_error = progress_adapter.error.get();
    if (!search_error.empty())
      message += " (" + search_error + ")";
    if (!progress_error.empty())
      message += " (" + progress_error + ")";
    fail(output, status, message);
    return false;
  }
  copyResults(output, ctx.get(), packed);
  return true;
}

template <typename PointInT, typename PointOutT>
void
DACPONormalOrientation<PointInT, PointOutT>::computeFeature(PointCloudOut& output)
{
  clearResults();
  if (!checkSetup(output))
    return;
  Packed packed;
  packPoints(output, packed);
  if (!checkPacked(output, packed))
    return;

  dacpo_params params = getParameters();
  if (use_sensor_origin_)
    for (int d = 0; d < 3; ++d)
      params.viewpoint[d] = static_cast<double>(input_->sensor_origin_[d]);
  if (!orientPacked(output, params, packed))
    return;
  warnAboutRun(params);
}

} // namespace pcl

#define PCL_INSTANTIATE_DACPONormalOrientation(T, OutT)                                \
  template class PCL_EXPORTS pcl::DACPONormalOrientation<T, OutT>;
