/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_normal_orientation.h
 * \brief pcl::DACPONormalOrientation: globally consistent normal orientation of
 * open, scene-level point clouds with the DACPO method (TOG 2025), as a PCL
 * feature.
 *
 * The class is a thin wrapper around the C core (<dacpo/dacpo.h>): it packs the
 * finite points of the input, feeds the core PCL's neighbour search
 * (pcl::search::KdTree, i.e. FLANN, unless another search is set) and copies the
 * oriented normals back in the caller's point order.
 */
#pragma once

#include <dacpo/dacpo.h>

#include <pcl/conversions.h>
#include <pcl/features/feature.h>
#include <pcl/memory.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/PolygonMesh.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pcl {

namespace dacpo {
/* C++ names of the C core's enums (same values), shared by every
 * DACPONormalOrientation<PointInT, PointOutT>. */
/** \brief Outcome of compute() (the values of the C core's dacpo_status). */
enum class Status : int {
  OK = DACPO_OK,
  InvalidArgument = DACPO_ERR_INVALID_ARGUMENT,
  EmptyInput = DACPO_ERR_EMPTY_INPUT,
  NonFiniteInput = DACPO_ERR_NONFINITE_INPUT,
  TooFewPoints = DACPO_ERR_TOO_FEW_POINTS,
  Disconnected = DACPO_ERR_DISCONNECTED,
  NeighborSearch = DACPO_ERR_NEIGHBOR_SEARCH,
  Solver = DACPO_ERR_SOLVER,
  OutOfMemory = DACPO_ERR_OUT_OF_MEMORY,
  Cancelled = DACPO_ERR_CANCELLED,
  Internal = DACPO_ERR_INTERNAL
};
/** \brief Consistency measure of the block-graph edges (dacpo_edge_weight). */
enum class EdgeWeight : int {
  DipoleBoundary = DACPO_WEIGHT_DIPOLE_BOUNDARY,
  VCR = DACPO_WEIGHT_VCR, ///< visible connected regions (paper, default)
  Overlap = DACPO_WEIGHT_OVERLAP
};
/** \brief Which of the two consistent orientations is returned (dacpo_sign_policy). */
enum class SignPolicy : int {
  FreeSpace = DACPO_SIGN_FREE_SPACE, ///< face the free space seen from (default)
  ViewPoint = DACPO_SIGN_VIEWPOINT,  ///< most normals face setViewPoint()
  Keep = DACPO_SIGN_KEEP             ///< the method's arbitrary sign
};
/** \brief Disconnected k-NN graphs (dacpo_disconnected_policy). */
enum class DisconnectedPolicy : int {
  Separate = DACPO_DISCONNECTED_SEPARATE,  ///< relative sign undefined
  Error = DACPO_DISCONNECTED_ERROR,        ///< fail with Status::Disconnected
  Bridge = DACPO_DISCONNECTED_BRIDGE,      ///< join along the Euclidean MST
  ViewPoint = DACPO_DISCONNECTED_VIEWPOINT ///< face the implied viewpoint (default)
};
} // namespace dacpo

/**
 * \brief Orients point normals consistently over a whole scene with DACPO
 * ("A Divide-and-Conquer Approach for Global Orientation of Non-Watertight
 * Scene-Level Point Clouds Using 0-1 Integer Optimization", TOG 2025).
 *
 * The cloud is cut into spatially connected blocks, each block is oriented on its
 * own (dipole-field initialisation, then iterative Poisson refinement), and a 0-1
 * program over the block graph decides which blocks to flip.
 *
 * Normal axes, two ways:
 * - setInputNormals() given (any cloud with normal_x/y/z indexed like the input,
 *   e.g. pcl::PointCloud<pcl::Normal> from pcl::NormalEstimation, or the input
 *   cloud itself when it is a pcl::PointNormal cloud): those axes are oriented,
 *   their signs are ignored, and the output curvature is copied from them (0 if
 *   their type has no curvature).
 * - otherwise the core estimates PCA normals from the getNormalK() nearest
 *   neighbours and the output curvature is the PCA surface variation.
 *
 * The neighbour graph the method works on has k = getKSearch() (default 10)
 * neighbours per point; radius search is not supported. The search runs on the
 * input cloud; a different search surface is rejected.
 *
 * Output: one point per entry of the indices (input order). Fields that
 * PointInT and PointOutT share (x, y, z, rgb, ...) are copied from the input;
 * normal_x/y/z are set to the oriented unit normal, and curvature when PointOutT
 * has it. Points with a non-finite coordinate, or a non-finite or zero input
 * normal, are skipped: they get NaN normals and curvature, and the output is
 * then not dense.
 *
 * Several connected components of the k-NN graph are oriented separately, then
 * each takes the sign under which its points face the viewpoint implied by the
 * largest component (DisconnectedPolicy::ViewPoint, the default);
 * setDisconnectedPolicy() chooses otherwise. A PCL_WARN reports the count and how
 * many parts were related; getComponentLabels() tells them apart.
 *
 * Runs with the same parameters and seed give identical output, also with a
 * different number of threads.
 *
 * \code
 * pcl::DACPONormalOrientation<pcl::PointXYZ, pcl::Normal> dacpo;
 * dacpo.setInputCloud(cloud);
 * dacpo.setInputNormals(normals); // optional
 * pcl::PointCloud<pcl::Normal> oriented;
 * dacpo.compute(oriented);
 * \endcode
 *
 * \tparam PointInT  point type with x, y, z
 * \tparam PointOutT point type with normal_x, normal_y, normal_z (and curvature)
 */
template <typename PointInT, typename PointOutT>
class DACPONormalOrientation : public Feature<PointInT, PointOutT> {
public:
  using Status = dacpo::Status;
  using EdgeWeight = dacpo::EdgeWeight;
  using SignPolicy = dacpo::SignPolicy;
  using DisconnectedPolicy = dacpo::DisconnectedPolicy;

  /** \brief Fixed English text of a status. */
  static const char*
  statusString(Status status)
  {
    return dacpo_status_string(static_cast<dacpo_status>(status));
  }

  using Ptr = shared_ptr<DACPONormalOrientation<PointInT, PointOutT>>;
  using ConstPtr = shared_ptr<const DACPONormalOrientation<PointInT, PointOutT>>;
  using PointCloudIn = typename Feature<PointInT, PointOutT>::PointCloudIn;
  using PointCloudOut = typename Feature<PointInT, PointOutT>::PointCloudOut;

  /**
   * \brief Progress callback: the stage running and the fraction done in [0, 1].
   * Called on the thread that runs compute(). Return false to cancel the run
   * (compute() then fails with ::DACPO_ERR_CANCELLED and an empty output).
   */
  using ProgressCallback = std::function<bool(dacpo_stage stage, double fraction)>;

  /** \brief Default parameters (dacpo_params_init()) and k = 10. */
  DACPONormalOrientation();

  /**
   * \brief Give the normal axes to orient (signs are ignored).
   * \param[in] normals a cloud with normal_x/y/z, one point per input point
   *            (indexed like the input cloud, not like the indices). The cloud
   *            is held, not copied, until resetInputNormals() or the next call.
   */
  template <typename PointNT>
  void
  setInputNormals(const shared_ptr<const PointCloud<PointNT>>& normals)
  {
    static_assert(pcl::traits::has_normal_v<PointNT>,
                  "setInputNormals needs a point type with normal_x/y/z");
    if (!normals) {
      resetInputNormals();
      return;
    }
    normals_holder_ = normals;
    normals_size_ = normals->size();
    normals_reader_ = &DACPONormalOrientation::readNormal<PointNT>;
  }

  /** \brief Overload for a non-const cloud pointer. */
  template <typename PointNT>
  void
  setInputNormals(const shared_ptr<PointCloud<PointNT>>& normals)
  {
    setInputNormals<PointNT>(shared_ptr<const PointCloud<PointNT>>(normals));
  }

  /** \brief Forget the input normals: the next compute() estimates PCA normals. */
  void
  resetInputNormals()
  {
    normals_holder_.reset();
    normals_size_ = 0;
    normals_reader_ = nullptr;
  }

  /** \brief True if setInputNormals() gave normals for the next compute(). */
  bool
  hasInputNormals() const
  {
    return static_cast<bool>(normals_holder_);
  }

  /** \brief Neighbours for PCA normals when none are given (default 16, >= 3). */
  void
  setNormalK(std::size_t normal_k)
  {
    params_.normal_k = normal_k;
  }
  /** \brief See setNormalK(). */
  std::size_t
  getNormalK() const
  {
    return params_.normal_k;
  }

  /** \brief Estimated normals: per point the flattest of 3/4, 1 and 3/2 x
   *  normal_k neighbours (lowest surface variation, no strips); see
   *  dacpo_params.adaptive_normals. */
  void
  setAdaptiveNormals(bool on)
  {
    params_.adaptive_normals = on ? 1 : 0;
  }
  /** \brief See setAdaptiveNormals(). */
  bool
  getAdaptiveNormals() const
  {
    return params_.adaptive_normals != 0;
  }

  /** \brief Target number of blocks; 0 = automatic, n/625 in [1, 400] (default 0). */
  void
  setNumberOfBlocks(std::size_t num_blocks)
  {
    params_.num_blocks = num_blocks;
  }
  /** \brief See setNumberOfBlocks(). */
  std::size_t
  getNumberOfBlocks() const
  {
    return params_.num_blocks;
  }

  /** \brief Width of the overlap ring around each block, in k-NN hops (default 3). */
  void
  setRingHops(std::size_t ring_hops)
  {
    params_.ring_hops = ring_hops;
  }
  /** \brief See setRingHops(). */
  std::size_t
  getRingHops() const
  {
    return params_.ring_hops;
  }

  /** \brief Constant c of the dipole field (paper Eq. 1), >= 1 (default -1: by
   * the scan kind, 1 for a single depth view, 1.5 otherwise). Larger values keep
   * thin two-sided structures apart, smaller ones resist noise; 1 drops the
   * stacked term's "opposite" vote (no part of one view shows two faces). */
  void
  setDipoleC(double c)
  {
    params_.dipole_c = c;
  }
  /** \brief See setDipoleC(). */
  double
  getDipoleC() const
  {
    return params_.dipole_c;
  }

  /** \brief Number M of randomized propagation orders per block (default 5). */
  void
  setDipoleOrders(std::size_t orders)
  {
    params_.dipole_orders = orders;
  }
  /** \brief See setDipoleOrders(). */
  std::size_t
  getDipoleOrders() const
  {
    return params_.dipole_orders;
  }

  /** \brief Nearest already placed points summed per dipole decision (default 32). */
  void
  setDipoleNeighbors(std::size_t neighbors)
  {
    params_.dipole_neighbors = neighbors;
  }
  /** \brief See setDipoleNeighbors(). */
  std::size_t
  getDipoleNeighbors() const
  {
    return params_.dipole_neighbors;
  }

  /** \brief Re-decision sweeps after the vote of the orders, repeated until no
   *  point changes (at most 10; default true). */
  void
  setDipoleFinalSweep(bool enabled)
  {
    params_.dipole_final_sweep = enabled ? 10 : 0;
  }
  /** \brief See setDipoleFinalSweep(). */
  bool
  getDipoleFinalSweep() const
  {
    return params_.dipole_final_sweep != 0;
  }

  /** \brief Run stage 3, iterative Poisson refinement per block (default true). */
  void
  setIPSREnabled(bool enabled)
  {
    params_.ipsr_enabled = enabled ? 1 : 0;
  }
  /** \brief See setIPSREnabled(). */
  bool
  getIPSREnabled() const
  {
    return params_.ipsr_enabled != 0;
  }

  /** \brief Iteration cap of the Poisson refinement per block (default 20). */
  void
  setIPSRMaxIterations(std::size_t iterations)
  {
    params_.ipsr_max_iterations = iterations;
  }
  /** \brief See setIPSRMaxIterations(). */
  std::size_t
  getIPSRMaxIterations() const
  {
    return params_.ipsr_max_iterations;
  }

  /** \brief Consistency measure of the block-graph edges (default
   *  EdgeWeight::VCR, the paper's visible connected regions). */
  void
  setEdgeWeight(EdgeWeight weight)
  {
    params_.edge_weight = static_cast<dacpo_edge_weight>(weight);
  }
  /** \brief See setEdgeWeight(). */
  EdgeWeight
  getEdgeWeight() const
  {
    return static_cast<EdgeWeight>(params_.edge_weight);
  }

  /**
   * \brief Seconds allowed to the 0-1 program (default 30). When it runs out the
   * best feasible answer is used and a PCL_WARN says it is not proven optimal.
   */
  void
  setSolverTimeLimit(double seconds)
  {
    params_.solver_time_limit = seconds;
  }
  /** \brief See setSolverTimeLimit(). */
  double
  getSolverTimeLimit() const
  {
    return params_.solver_time_limit;
  }

  /** \brief Seed all randomness derives from (default 1). */
  void
  setSeed(std::uint64_t seed)
  {
    params_.seed = seed;
  }
  /** \brief See setSeed(). */
  std::uint64_t
  getSeed() const
  {
    return params_.seed;
  }

  /**
   * \brief Worker threads; 0 = all cores (default), as in NormalEstimationOMP.
   * The search method is then queried from several threads at once.
   */
  void
  setNumberOfThreads(unsigned int num_threads = 0)
  {
    params_.num_threads = num_threads;
  }
  /** \brief See setNumberOfThreads(). */
  unsigned int
  getNumberOfThreads() const
  {
    return params_.num_threads;
  }

  /** \brief Independent runs of the dipole stage per block (default 16),
   *  voted point by point; they stop once the first four agree. */
  void
  setDipoleRestarts(std::size_t restarts)
  {
    params_.dipole_restarts = restarts;
  }
  /** \brief See setDipoleRestarts(). */
  std::size_t
  getDipoleRestarts() const
  {
    return params_.dipole_restarts;
  }

  /** \brief Block-graph edges with less than this fraction of the median
   *  edge's evidence leave the relative sign of the block groups they join to
   *  the viewpoint vote (DisconnectedPolicy::ViewPoint only; 0 = only
   *  disconnected parts; default 1: every edge below the median). A part
   *  follows the vote only when its margin is >= 0.3. */
  void
  setWeakEdgeFraction(double fraction)
  {
    params_.weak_edge_fraction = fraction;
  }
  /** \brief See setWeakEdgeFraction(). */
  double
  getWeakEdgeFraction() const
  {
    return params_.weak_edge_fraction;
  }

  /** \brief Which of the two consistent orientations to return (default
   *  SignPolicy::FreeSpace: normals face the free space the scan was seen from,
   *  no sensor position needed; closed objects get outward normals; in a
   *  single depth view whose density places its sensor well, every point the
   *  sensor sees squarely faces it). */
  void
  setSignPolicy(SignPolicy policy)
  {
    params_.sign_policy = static_cast<dacpo_sign_policy>(policy);
    if (policy != SignPolicy::ViewPoint)
      use_sensor_origin_ = false;
  }
  /** \brief See setSignPolicy(). */
  SignPolicy
  getSignPolicy() const
  {
    return static_cast<SignPolicy>(params_.sign_policy);
  }

  /** \brief Make most normals face (vpx, vpy, vpz), as PCL's NormalEstimation
   *  does, but with one sign for the whole cloud so consistency is kept
   *  (sets SignPolicy::ViewPoint). */
  void
  setViewPoint(float vpx, float vpy, float vpz)
  {
    params_.sign_policy = DACPO_SIGN_VIEWPOINT;
    params_.viewpoint[0] = vpx;
    params_.viewpoint[1] = vpy;
    params_.viewpoint[2] = vpz;
    use_sensor_origin_ = false;
  }
  /** \brief The viewpoint set by setViewPoint() (0, 0, 0 if none). */
  void
  getViewPoint(float& vpx, float& vpy, float& vpz) const
  {
    vpx = static_cast<float>(params_.viewpoint[0]);
    vpy = static_cast<float>(params_.viewpoint[1]);
    vpz = static_cast<float>(params_.viewpoint[2]);
  }
  /** \brief Face the input cloud's sensor_origin_ (read at compute() time;
   *  sets SignPolicy::ViewPoint). */
  void
  useSensorOriginAsViewPoint()
  {
    params_.sign_policy = DACPO_SIGN_VIEWPOINT;
    use_sensor_origin_ = true;
  }

  /** \brief What to do with a disconnected k-NN graph (default: relate the parts
   *  by the viewpoint the largest one implies, DisconnectedPolicy::ViewPoint). */
  void
  setDisconnectedPolicy(DisconnectedPolicy policy)
  {
    params_.disconnected = static_cast<dacpo_disconnected_policy>(policy);
  }
  /** \brief See setDisconnectedPolicy(). */
  DisconnectedPolicy
  getDisconnectedPolicy() const
  {
    return static_cast<DisconnectedPolicy>(params_.disconnected);
  }

  /** \brief VCR image side in pixels (default 128; the paper: 400 for 200 blocks). */
  void
  setVCRImageSize(std::size_t pixels)
  {
    params_.vcr_image_size = pixels;
  }
  /** \brief See setVCRImageSize(). */
  std::size_t
  getVCRImageSize() const
  {
    return params_.vcr_image_size;
  }

  /** \brief Number of VCR views (default 12: the dodecahedron face centres). */
  void
  setVCRViews(std::size_t views)
  {
    params_.vcr_views = views;
  }
  /** \brief See setVCRViews(). */
  std::size_t
  getVCRViews() const
  {
    return params_.vcr_views;
  }

  /** \brief Keep the reconstructed surface: one mesh over all blocks, rebuilt from
   * the final normals and wound like them (default false); see getMesh(). */
  void
  setKeepMesh(bool keep)
  {
    params_.keep_mesh = keep ? 1 : 0;
  }
  /** \brief See setKeepMesh(). */
  bool
  getKeepMesh() const
  {
    return params_.keep_mesh != 0;
  }


  /** \brief Thin two-sided parts (default -1: by the scan kind, 0 for a single depth
   * view, 3 otherwise; 0 = off): neighbours with parallel axes
   * that lie off each other's tangent plane by more than this many times the local
   * noise (and 0.5 to 2 local spacings), beneath one another, are taken as the two
   * faces of one thin part and made to face opposite ways. */
  void
  setDipoleTwoSheet(double factor)
  {
    params_.dipole_two_sheet = factor;
  }
  /** \brief See setDipoleTwoSheet(). */
  double
  getDipoleTwoSheet() const
  {
    return params_.dipole_two_sheet;
  }

  /** \brief Dipole constant for geometry in blocks with thin two-sided parts
   * (default 4, 0 = off): where >= 3 % of a block's points have a second sheet
   * beneath them, neighbour pairs lying off each other's tangent plane by more
   * than the two-sheet noise test (setDipoleTwoSheet() x local noise) use this c
   * in Eq. 1 instead of setDipoleC()'s; blocks seen from one side (single depth
   * frames) keep setDipoleC(). See dacpo_params.dipole_c_thin. */
  void
  setDipoleCThin(double c)
  {
    params_.dipole_c_thin = c;
  }
  /** \brief See setDipoleCThin(). */
  double
  getDipoleCThin() const
  {
    return params_.dipole_c_thin;
  }

  /** \brief Layered surfaces seen from one side (default -1: by the scan kind,
   * 0.5 for a single depth view, 2 otherwise; 0 = off): neighbours with parallel
   * axes more than this many local spacings off each other's tangent plane are
   * layers of one surface (depth quantisation) and no longer vote for opposite
   * orientations (Eq. 1 with c = 1), in blocks where under 3 % of the points have
   * a second sheet beneath them. Measured (15 depth frames / 18 synthetic rooms,
   * % wrong, one value for both): off 4.80 / 7.95, 2 3.66 / 8.01, 0.5 2.72 / 8.30. */
  void
  setDipoleLayers(double spacings)
  {
    params_.dipole_layers = spacings;
  }
  /** \brief See setDipoleLayers(). */
  double
  getDipoleLayers() const
  {
    return params_.dipole_layers;
  }

  /** \brief The kind of scan (default DACPO_SCAN_AUTO: decided from the sampling
   * density, see dacpo_stats::scan_kind): DACPO_SCAN_SINGLE_VIEW for one depth
   * frame (layers face one way; the thin-part side cue only where a block shows
   * it clearly), DACPO_SCAN_MULTI_VIEW for fused scans and sampled scenes (the
   * side cue in every block). Set it for a depth frame thinned to a coarse voxel
   * grid, which no longer looks like one view. */
  void
  setScanKind(dacpo_scan_kind kind)
  {
    params_.scan_kind = kind;
  }
  /** \brief See setScanKind(). */
  dacpo_scan_kind
  getScanKind() const
  {
    return params_.scan_kind;
  }

  /** \brief Parts thinner than the point spacing (default 0.001, 0 = off; 0.5
   * for a stronger field): where the neighbours of a point with parallel
   * axes lie on two parallel copies of one smooth surface over 0.3 spacing
   * apart, the pairs across the copies face opposite ways, the point's normal
   * leans away from the other copy with this weight (against the sum of its
   * pair energies), and stage 3 keeps that normal. Only in blocks where the cue
   * fires on >= 5 % of the points (single depth frames: <= 3.5 %). See
   * dacpo_params.dipole_sides for the measurements. */
  void
  setDipoleSides(double weight)
  {
    params_.dipole_sides = weight;
  }
  /** \brief See setDipoleSides(). */
  double
  getDipoleSides() const
  {
    return params_.dipole_sides;
  }

  /** \brief Weight of the side cue as an absolute sign in the 0-1 program
   * (default 1, 0 = off): a block where the cue fired on >= 20 points is tied
   * to the sign its cue points give it (the faces of a thin part look away from
   * each other), scaled like an edge. See dacpo_params.cue_anchor. */
  void
  setCueAnchor(double weight)
  {
    params_.cue_anchor = weight;
  }
  /** \brief See setCueAnchor(). */
  double
  getCueAnchor() const
  {
    return params_.cue_anchor;
  }

  /** \brief With EdgeWeight::VCR: the dipole energy across each block seam
   * is added to the VCR evidence as a second measure with this weight (each
   * in units of its typical edge; default 0.5); 0 = VCR alone. See
   * dacpo_params.seam_dipole. */
  void
  setSeamDipole(double weight)
  {
    params_.seam_dipole = weight;
  }
  /** \brief See setSeamDipole(). */
  double
  getSeamDipole() const
  {
    return params_.seam_dipole;
  }

  /** \brief After the 0-1 program, every smooth surface of at least
   * \a min_points points (neighbouring axes within 8 degrees, each neighbour
   * in the other's tangent plane) turns over its points that face against
   * its majority, unless they are over a fifth of it (default 500); 0 =
   * off. See dacpo_params.surface_vote. */
  void
  setSurfaceVote(std::size_t min_points)
  {
    params_.surface_vote = min_points;
  }
  /** \brief See setSurfaceVote(). */
  std::size_t
  getSurfaceVote() const
  {
    return params_.surface_vote;
  }

  /**
   * \brief Set every core parameter at once. params.k replaces setKSearch();
   * params.estimate_normals is ignored (decided by setInputNormals()).
   */
  void
  setParameters(const dacpo_params& params)
  {
    params_ = params;
    this->k_ = static_cast<int>(params.k);
  }
  /**
   * \brief Set one core parameter by its dacpo_params name from text, as the
   * command line does: setParameter("dipole_c", "2"), setParameter("scan_kind",
   * "single") (dacpo_params_set(): every row of dacpo_param_table.h). "k" sets
   * the k-NN size as setKSearch() does.
   * \return false, with the reason in \a error when given, for an unknown name
   * or a value the field cannot hold (nothing changes then).
   */
  bool
  setParameter(const std::string& name, const std::string& value, std::string* error = nullptr)
  {
    dacpo_params p = getParameters();
    char msg[256] = "";
    if (dacpo_params_set(&p, name.c_str(), value.c_str(), msg, sizeof(msg)) != DACPO_OK) {
      if (error)
        *error = msg;
      return false;
    }
    setParameters(p);
    return true;
  }

  /** \brief The parameters the next compute() passes to the core (k from getKSearch()).
   */
  dacpo_params
  getParameters() const
  {
    dacpo_params p = params_;
    p.k = this->k_ > 0 ? static_cast<std::size_t>(this->k_) : 0;
    p.estimate_normals = hasInputNormals() ? 0 : 1;
    return p;
  }

  /** \brief Called during compute(); an empty function (default) disables it. */
  void
  setProgressCallback(const ProgressCallback& callback)
  {
    progress_ = callback;
  }

  /** \brief Status of the last compute() (Status::OK on success). */
  Status
  getLastStatus() const
  {
    return static_cast<Status>(last_status_);
  }
  /** \brief Message of the last failure, "" after a success. */
  const std::string&
  getLastError() const
  {
    return last_error_;
  }

  /** \brief Core statistics of the last compute() (timings per stage, blocks, ...). */
  dacpo_stats
  getStats() const
  {
    return stats_;
  }

  /**
   * \brief Connected component of each output point in the last compute(), in
   * output order; -1 for skipped (non-finite) points. Empty after a failure.
   */
  const std::vector<int>&
  getComponentLabels() const
  {
    return component_labels_;
  }

  /**
   * \brief How sure the last compute() is of each output point's sign, in
   * [0, 1] (see dacpo_ctx_point_confidence()); NaN for skipped points, empty
   * after a failure. The least confident points hold most of the wrong ones.
   */
  const std::vector<float>&
  getPointConfidence() const
  {
    return point_confidence_;
  }

  /** \brief Block of each output point (as getComponentLabels()). */
  const std::vector<int>&
  getBlockLabels() const
  {
    return block_labels_;
  }

  /** \brief Per block: 1 if the 0-1 program flipped it (getStats().num_blocks entries).
   */
  const std::vector<std::uint8_t>&
  getBlockFlips() const
  {
    return block_flips_;
  }

  /** \brief Block-graph edges of the last compute() with their weights. */
  const std::vector<dacpo_edge_info>&
  getEdges() const
  {
    return edges_;
  }

  /** \brief Scene mesh of the last compute() with setKeepMesh(true): x, y, z per
   * vertex (same frame as the input). Empty otherwise. */
  const std::vector<float>&
  getMeshVertices() const
  {
    return mesh_vertices_;
  }

  /** \brief Scene mesh triangles: three indices into getMeshVertices() each. */
  const std::vector<std::int32_t>&
  getMeshTriangles() const
  {
    return mesh_triangles_;
  }

  /** \brief The scene mesh of the last compute() with setKeepMesh(true) as a
   *  pcl::PolygonMesh (vertex cloud x y z, triangles wound like the output
   *  normals), ready for pcl::io::savePLYFile or the PCL visualizer. One
   *  surface over all blocks: no cracks along block seams; open only at the
   *  scene's own rims and holes. Returns
   *  false (and leaves \a mesh empty) when there is none. */
  bool
  getMesh(pcl::PolygonMesh& mesh) const
  {
    mesh = pcl::PolygonMesh();
    if (mesh_triangles_.empty())
      return false;
    pcl::PointCloud<pcl::PointXYZ> vertices;
    vertices.resize(mesh_vertices_.size() / 3);
    for (std::size_t i = 0; i < vertices.size(); ++i)
      vertices[i].getVector3fMap() << mesh_vertices_[3 * i], mesh_vertices_[3 * i + 1],
          mesh_vertices_[3 * i + 2];
    pcl::toPCLPointCloud2(vertices, mesh.cloud);
    mesh.polygons.resize(mesh_triangles_.size() / 3);
    for (std::size_t t = 0; t < mesh.polygons.size(); ++t)
      mesh.polygons[t].vertices = {
          static_cast<pcl::index_t>(mesh_triangles_[3 * t]),
          static_cast<pcl::index_t>(mesh_triangles_[3 * t + 1]),
          static_cast<pcl::index_t>(mesh_triangles_[3 * t + 2])};
    return true;
  }

protected:
  using Feature<PointInT, PointOutT>::feature_name_;
  using Feature<PointInT, PointOutT>::getClassName;
  using Feature<PointInT, PointOutT>::indices_;
  using Feature<PointInT, PointOutT>::input_;
  using Feature<PointInT, PointOutT>::surface_;
  using Feature<PointInT, PointOutT>::fake_surface_;
  using Feature<PointInT, PointOutT>::tree_;
  using Feature<PointInT, PointOutT>::k_;
  using Feature<PointInT, PointOutT>::search_radius_;

  /** \brief Orient the normals of the points of indices_ into \a output. */
  void
  computeFeature(PointCloudOut& output) override;

  /** \brief PCL's own checks (input set, search parameters), with their verdict
   *  in getLastStatus() / getLastError() too: compute() returns early on them. */
  bool
  initCompute() override;

private:
  /** \brief Reads normal i of the held normals cloud: axis and curvature. */
  using NormalReader = void (*)(const void* cloud,
                                std::size_t i,
                                float normal[3],
                                float* curvature);

  template <typename PointNT>
  static void
  readNormal(const void* cloud, std::size_t i, float normal[3], float* curvature)
  {
    const PointNT& p = (*static_cast<const PointCloud<PointNT>*>(cloud))[i];
    normal[0] = p.normal_x;
    normal[1] = p.normal_y;
    normal[2] = p.normal_z;
    if constexpr (pcl::traits::has_curvature_v<PointNT>)
      *curvature = p.curvature;
    else
      *curvature = 0.0f;
  }

  /** \brief Clears the output and logs a failure of the run. */
  void
  fail(PointCloudOut& output, dacpo_status status, const std::string& message);

  /** \brief The usable points (finite, with a usable axis when normals are given),
   *  packed for the C core, and where each one came from / goes. */
  struct Packed {
    std::vector<pcl::index_t> local_to_cloud;
    std::vector<std::size_t> local_to_out;
    std::vector<float> xyz, nrm, given_curvature;
  };
  /** \brief Forgets the status, stats and results of the previous run. */
  void
  clearResults();
  /** \brief Empties the per-point labels, edges and mesh of the previous run. */
  void
  clearLabels();
  /** \brief Rejects the set-ups DACPO does not support (false: output failed). */
  bool
  checkSetup(PointCloudOut& output);
  /** \brief Copies every input point to output (normals NaN) and packs the usable
   *  ones; output.is_dense tells whether all were. */
  void
  packPoints(PointCloudOut& output, Packed& packed) const;
  /** \brief Rejects an empty or too large packed cloud (false: output failed); warns
   *  when k is not smaller than the usable points. */
  bool
  checkPacked(PointCloudOut& output, const Packed& packed);
  /** \brief Runs the core on the packed points with the search and progress
   *  adapters and copies its results (false: output failed). */
  bool
  orientPacked(PointCloudOut& output, const dacpo_params& params, Packed& packed);
  /** \brief Normals, curvature, labels, confidence, flips, edges and mesh of a run. */
  void
  copyResults(PointCloudOut& output, const dacpo_ctx* ctx, const Packed& packed);
  /** \brief Warnings about disconnected parts and a solver time-out. */
  void
  warnAboutRun(const dacpo_params& params) const;

  dacpo_params params_;
  bool use_sensor_origin_ = false;
  ProgressCallback progress_;

  /** Type-erased input normals: the cloud (kept alive), its size and a reader. */
  shared_ptr<const void> normals_holder_;
  std::size_t normals_size_ = 0;
  NormalReader normals_reader_ = nullptr;

  dacpo_status last_status_ = DACPO_OK;
  std::string last_error_;
  dacpo_stats stats_;
  std::vector<int> component_labels_;
  std::vector<float> point_confidence_;
  std::vector<int> block_labels_;
  std::vector<std::uint8_t> block_flips_;
  std::vector<dacpo_edge_info> edges_;
  std::vector<float> mesh_vertices_;
  std::vector<std::int32_t> mesh_triangles_;
};

} // namespace pcl

#ifdef PCL_NO_PRECOMPILE
#include <pcl_dacpo/impl/dacpo_normal_orientation.hpp>
#endif
