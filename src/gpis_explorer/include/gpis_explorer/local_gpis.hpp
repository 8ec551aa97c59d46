// Local GP implicit surface for the ground-station budget: the GPIS of 000
// (eq. 33-40: IMQ kernel, labels 0 / -1, posterior mean and variance,
// gradient, Hessian, curvature) approximated by local GPs over a quadtree with
// overlap blending, after GPisMap (B. Lee, C. Zhang, Z. Huang, D. D. Lee,
// "Online Continuous Mapping using Gaussian Process Implicit Surfaces",
// ICRA 2019: the points are kept in a quadtree, each leaf holds
// a local GP over its points and those of a margin around it, a query is
// answered by blending the predictions of the local GPs around it, and a new
// point refits only the local GPs whose region it falls in).
//
// GPisMap's observation model is not 000's (labels 0 / -1), so only the
// partition, the margin, the blending and the incremental refit are taken
// from it; the rest are our choices:
//  - a leaf splits into four when more than `leaf_points` training points lie
//    in its box and its side is at least 2 min_leaf_size; while all points fit
//    in one leaf (every flight of the shipped rooms) the one local GP IS the
//    exact GP over all points, in the same point order: same numbers;
//  - the local GP of a leaf is the exact GP (class Gpis, 000 eq. 33-35) over
//    the points inside its box grown by `overlap` on every side, plus the
//    `label_neighbours` points of each label nearest to its centre (a leaf
//    outside a wall holds only surface points, labels 0, whose GP is ~0
//    everywhere and whose sign would be noise; the nearest interior points
//    give it the side; and the IMQ kernel is long range, so the points
//    beyond the margin still shape the exact mean: 96 per label cut the
//    near-surface mean error against the exact GP ~6x from 8 per label);
//  - blending: weight w_j(x) = s(t_x) s(t_y), t = distance to the nearest side
//    of the grown box / (2 overlap) clamped to [0, 1], s the C2 smoothstep
//    6t^5 - 15t^4 + 10t^3; mean = sum w_j m_j / sum w_j, variance =
//    sum w_j var_j / sum w_j (a partition of unity: the blended mean has the
//    continuous gradient and Hessian that eq. 36-40 need; its derivatives
//    include the weights' derivatives). Where one leaf alone covers x its
//    prediction is returned unchanged;
//  - incremental: a new point is added (incremental Cholesky row, Gpis::
//    add_point) to every local GP whose grown box contains it; a leaf that
//    overflows splits and its children are fitted; leaves whose nearest
//    points of a label changed are refitted. The boxes of every changed local
//    GP are reported (dirty_boxes()) so a grid needs recomputing there only.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "gpis_explorer/gpis.hpp"

namespace gpis_explorer {

struct LocalGpisParams {
  /// A leaf holding more training points than this splits into four
  /// (GPisMap's leaf capacity; the value is our choice: with the other
  /// defaults a 10,000-point room keeps local GPs of ~300-700 points).
  std::size_t leaf_points = 256;
  /// Margin [m] by which a leaf's box is grown for its local GP's points and
  /// its blending weight (GPisMap's overlap; our value).
  double overlap = 0.125;
  /// Leaves are not split below this side [m] (dense clusters, repeated
  /// points). Must be >= 2 overlap so a weight's ramps never meet.
  double min_leaf_size = 0.25;
  /// Points of each label nearest to a leaf's centre added to its local GP
  /// (our choice, see above: 8 -> 96 lowered the near-surface mean error at
  /// 2000 points from 0.077 to 0.012, the 10,000-point update from 0.17 to
  /// 0.24 s).
  std::size_t label_neighbours = 96;

  /// Throws std::invalid_argument "LocalGpisParams.<field>: <reason>".
  void validate() const;
};

class LocalGpis {
 public:
  LocalGpis(const GpisParams& gpis, const LocalGpisParams& local);

  /// Brings the partition up to date with `points` (the explorer's store of
  /// points, appended to since the last call; any other change must be
  /// announced by invalidate()). `cover` is a box the root must contain (the
  /// prediction grid): a point or a cover outside the root rebuilds
  /// everything. Returns true when it rebuilt everything.
  bool sync(const Gpis& points, const Eigen::AlignedBox2d& cover);
  /// The stored points changed other than by appending: the next sync()
  /// rebuilds from scratch.
  void invalidate() { valid_ = false; }

  /// Grown boxes of the local GPs changed by the last sync() (empty after a
  /// rebuild: everything changed).
  const std::vector<Eigen::AlignedBox2d>& dirty_boxes() const { return dirty_; }

  /// Blended mean at the columns of Q (mean resized to Q.cols()). Queries no
  /// leaf covers (outside the root grown by overlap) get NaN.
  void mean_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& mean) const;
  /// Blended mean and variance at the columns of Q.
  void predict_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& mean,
                     Eigen::VectorXd& variance) const;
  /// Curvature (000 eq. 40) of the blended mean's level set at the columns
  /// of Q; NaN where |gradient| < min_gradient or no leaf covers.
  void curvature_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& kappa,
                       double min_gradient = 1e-9) const;
  double mean(const Eigen::Vector2d& x) const;
  /// Gradient of the blended mean (000 eq. 36-37 per local GP, with the
  /// weights' gradients).
  Eigen::Vector2d gradient(const Eigen::Vector2d& x) const;
  /// Mean, gradient and Hessian of the blended mean at x (000 eq. 34-39).
  void derivatives(const Eigen::Vector2d& x, double* mean, Eigen::Vector2d* gradient, Eigen::Matrix2d* hessian) const;

  std::size_t leaf_count() const { return leaves_.size(); }
  /// Points in the largest local GP.
  std::size_t largest_local() const;
  /// Bytes of the local GPs' state (points, factors) as allocated.
  std::size_t state_bytes() const;
  const LocalGpisParams& params() const { return lp_; }

 private:
  struct Leaf {
    Eigen::AlignedBox2d box;                ///< the leaf's own box
    std::vector<std::size_t> own;           ///< indices of the points in box
    std::vector<std::size_t> members;       ///< indices in the local GP, ascending
    std::unique_ptr<Gpis> gp;               ///< local GP (null: no point at all)
  };
  Eigen::AlignedBox2d grown(const Leaf& l) const;
  void rebuild(const Gpis& points, const Eigen::AlignedBox2d& cover);
  /// Splits leaf i (recursively) while it is over capacity; appends the
  /// children, erases i. Returns the leaves made.
  void split_until_fits(std::size_t i);
  /// The member set of a leaf from the points (grown box + neighbours).
  std::vector<std::size_t> member_set(const Leaf& l) const;
  void fit(Leaf& l, std::vector<std::size_t> members);
  /// Leaves whose grown box contains x, with their weights and weight
  /// derivatives (dw: d/dx, d/dy; hw: xx, xy, yy).
  struct Cover {
    std::size_t leaf;
    double w;
    Eigen::Vector2d dw;
    Eigen::Vector3d hw;
  };
  void covers(const Eigen::Vector2d& x, std::vector<Cover>& out) const;
  /// For each leaf with a GP, the query columns it covers and their weights.
  void assign(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, std::vector<std::vector<Eigen::Index>>& cols,
              std::vector<std::vector<double>>& weights) const;

  GpisParams gp_;
  LocalGpisParams lp_;
  const Gpis* points_ = nullptr;  ///< the store of the last sync()
  bool valid_ = false;
  std::size_t synced_ = 0;
  Eigen::AlignedBox2d root_;
  std::vector<Leaf> leaves_;
  std::vector<Eigen::AlignedBox2d> dirty_;
};

}  // namespace gpis_explorer
