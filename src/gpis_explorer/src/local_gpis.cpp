// Local GP implicit surface over a quadtree (GPisMap, Lee et al., ICRA 2019),
// each local GP the exact GPIS of 000 eq. 33-40. See local_gpis.hpp.
#include "gpis_explorer/local_gpis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace gpis_explorer {
namespace {

[[noreturn]] void fail(const char* field, const std::string& reason) {
  throw std::invalid_argument(std::string("LocalGpisParams.") + field + ": " + reason);
}

/// C2 smoothstep s(t) = 6t^5 - 15t^4 + 10t^3 on [0, 1] and its first two
/// derivatives (s, s', s'' vanish / saturate at both ends).
struct Step {
  double s, ds, dds;
};
Step smoothstep(double t) {
  if (t <= 0.0) return {0.0, 0.0, 0.0};
  if (t >= 1.0) return {1.0, 0.0, 0.0};
  const double t2 = t * t;
  return {t2 * t * (10.0 - 15.0 * t + 6.0 * t2), 30.0 * t2 * (1.0 - t) * (1.0 - t), 60.0 * t * (1.0 - t) * (1.0 - 2.0 * t)};
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

void LocalGpisParams::validate() const {
  if (leaf_points < 1 || leaf_points > 100000) {
    fail("leaf_points", "must be in [1, 100000], got " + std::to_string(leaf_points));
  }
  if (!(std::isfinite(overlap) && overlap > 0.0)) fail("overlap", "must be > 0 m, got " + std::to_string(overlap));
  if (!(std::isfinite(min_leaf_size) && min_leaf_size >= 2.0 * overlap)) {
    fail("min_leaf_size", "must be >= 2 overlap (" + std::to_string(2.0 * overlap) + " m) so the blending ramps of a "
         "leaf never meet, got " + std::to_string(min_leaf_size));
  }
  if (label_neighbours > 100000) fail("label_neighbours", "must be <= 100000, got " + std::to_string(label_neighbours));
}

LocalGpis::LocalGpis(const GpisParams& gpis, const LocalGpisParams& local) : gp_(gpis), lp_(local) {
  gp_.validate();
  lp_.validate();
}

Eigen::AlignedBox2d LocalGpis::grown(const Leaf& l) const {
  const Eigen::Vector2d m = Eigen::Vector2d::Constant(lp_.overlap);
  return {l.box.min() - m, l.box.max() + m};
}

std::vector<std::size_t> LocalGpis::member_set(const Leaf& l) const {
  const Gpis& P = *points_;
  const Eigen::AlignedBox2d g = grown(l);
  const Eigen::Vector2d c = l.box.center();
  std::vector<std::size_t> in;
  std::vector<std::pair<double, std::size_t>> near[2];
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Eigen::Vector2d p = P.point(i);
    if (g.contains(p)) {
      in.push_back(i);
    } else if (lp_.label_neighbours > 0) {
      near[P.label(i) == kSurfaceLabel ? 0 : 1].emplace_back((p - c).squaredNorm(), i);
    }
  }
  for (auto& v : near) {
    const std::size_t k = std::min(lp_.label_neighbours, v.size());
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    for (std::size_t j = 0; j < k; ++j) in.push_back(v[j].second);
  }
  std::sort(in.begin(), in.end());
  return in;
}

void LocalGpis::fit(Leaf& l, std::vector<std::size_t> members) {
  l.members = std::move(members);
  if (l.members.empty()) {
    l.gp.reset();
    return;
  }
  Eigen::Matrix2Xd X(2, static_cast<Eigen::Index>(l.members.size()));
  Eigen::VectorXd y(static_cast<Eigen::Index>(l.members.size()));
  for (std::size_t j = 0; j < l.members.size(); ++j) {
    X.col(static_cast<Eigen::Index>(j)) = points_->point(l.members[j]);
    y(static_cast<Eigen::Index>(j)) = points_->label(l.members[j]);
  }
  if (!l.gp) l.gp = std::make_unique<Gpis>(gp_);
  l.gp->fit(X, y);  // 000 eq. 34-35 over the leaf's points (blocked Cholesky)
}

void LocalGpis::split_until_fits(std::size_t i) {
  std::vector<Leaf> todo;
  todo.push_back(std::move(leaves_[i]));
  leaves_[i] = std::move(leaves_.back());
  leaves_.pop_back();
  while (!todo.empty()) {
    Leaf l = std::move(todo.back());
    todo.pop_back();
    const double side = l.box.sizes().x();
    if (l.own.size() <= lp_.leaf_points || side < 2.0 * lp_.min_leaf_size * (1.0 - 1e-9)) {
      leaves_.push_back(std::move(l));
      continue;
    }
    const Eigen::Vector2d c = l.box.center();
    Leaf kids[4];
    for (int q = 0; q < 4; ++q) {
      const Eigen::Vector2d lo((q & 1) ? c.x() : l.box.min().x(), (q & 2) ? c.y() : l.box.min().y());
      const Eigen::Vector2d hi((q & 1) ? l.box.max().x() : c.x(), (q & 2) ? l.box.max().y() : c.y());
      kids[q].box = Eigen::AlignedBox2d(lo, hi);
    }
    for (std::size_t k : l.own) {
      const Eigen::Vector2d p = points_->point(k);
      kids[(p.x() >= c.x() ? 1 : 0) | (p.y() >= c.y() ? 2 : 0)].own.push_back(k);
    }
    for (auto& kid : kids) todo.push_back(std::move(kid));
  }
}

void LocalGpis::rebuild(const Gpis& points, const Eigen::AlignedBox2d& cover) {
  Eigen::AlignedBox2d b = cover;
  for (std::size_t i = 0; i < points.size(); ++i) b.extend(points.point(i));
  // Root: a square of side min_leaf_size * 2^k, so every leaf side is
  // min_leaf_size * 2^j and the lookup cells (min_leaf_size) tile the leaves.
  const double extent = std::max(b.sizes().maxCoeff(), lp_.min_leaf_size) * (1.0 + 1e-9) + 1e-9;
  double side = lp_.min_leaf_size;
  while (side < extent) side *= 2.0;
  const Eigen::Vector2d h = Eigen::Vector2d::Constant(side / 2.0);
  root_ = Eigen::AlignedBox2d(b.center() - h, b.center() + h);
  leaves_.clear();
  Leaf r;
  r.box = root_;
  for (std::size_t i = 0; i < points.size(); ++i) r.own.push_back(i);
  leaves_.push_back(std::move(r));
  split_until_fits(0);
  for (auto& l : leaves_) fit(l, member_set(l));
  synced_ = points.size();
  valid_ = true;
  dirty_.clear();
}

bool LocalGpis::sync(const Gpis& points, const Eigen::AlignedBox2d& cover) {
  const bool same_store = points_ == &points;
  points_ = &points;
  const auto inside_root = [&](const Eigen::Vector2d& p) {
    return (p.array() >= root_.min().array()).all() && (p.array() < root_.max().array()).all();
  };
  bool rebuild_all = !valid_ || !same_store || points.size() < synced_ || !root_.contains(cover);
  for (std::size_t k = synced_; k < points.size() && !rebuild_all; ++k) rebuild_all = !inside_root(points.point(k));
  if (rebuild_all) {
    rebuild(points, cover);
    return true;
  }
  dirty_.clear();
  if (synced_ == points.size()) return false;
  // New points into their leaves' own lists; overflowing leaves split (their
  // children are refitted below with every leaf whose member set changed).
  std::vector<char> split(leaves_.size(), 0);
  for (std::size_t k = synced_; k < points.size(); ++k) {
    const Eigen::Vector2d p = points.point(k);
    for (std::size_t i = 0; i < leaves_.size(); ++i) {
      const Eigen::AlignedBox2d& b = leaves_[i].box;
      if ((p.array() >= b.min().array()).all() && (p.array() < b.max().array()).all()) {
        leaves_[i].own.push_back(k);
        break;
      }
    }
  }
  for (std::size_t i = leaves_.size(); i-- > 0;) {
    const Leaf& l = leaves_[i];
    if (l.own.size() > lp_.leaf_points && l.box.sizes().x() >= 2.0 * lp_.min_leaf_size * (1.0 - 1e-9)) {
      dirty_.push_back(grown(l));
      const std::size_t before = leaves_.size();
      split_until_fits(i);
      // The children (appended) have no GP yet: fit them.
      for (std::size_t j = before - 1; j < leaves_.size(); ++j) {
        if (!leaves_[j].gp && leaves_[j].members.empty()) fit(leaves_[j], member_set(leaves_[j]));
      }
    }
  }
  // Every other leaf: append the new points its member set gained
  // (incremental Cholesky rows), or refit when a label neighbour was displaced.
  for (auto& l : leaves_) {
    std::vector<std::size_t> m = member_set(l);
    if (m == l.members) continue;
    dirty_.push_back(grown(l));
    const bool appends = m.size() >= l.members.size() && std::equal(l.members.begin(), l.members.end(), m.begin()) &&
                         (m.size() == l.members.size() || m[l.members.size()] >= synced_);
    if (appends && l.gp) {
      bool ok = true;
      for (std::size_t j = l.members.size(); j < m.size() && ok; ++j) {
        ok = l.gp->add_point(points.point(m[j]), points.label(m[j])) == AddStatus::kAdded;  // 000 eq. 34-35
      }
      if (ok) {
        l.members = std::move(m);
        continue;
      }
    }
    fit(l, std::move(m));  // numerically singular row or a displaced neighbour: refit the leaf
  }
  synced_ = points.size();
  return false;
}

void LocalGpis::covers(const Eigen::Vector2d& x, std::vector<Cover>& out) const {
  out.clear();
  const double m = lp_.overlap, inv = 1.0 / (2.0 * m);
  for (std::size_t i = 0; i < leaves_.size(); ++i) {
    const Leaf& l = leaves_[i];
    if (!l.gp) continue;
    Step s[2];
    double sign[2];
    bool in = true;
    for (int a = 0; a < 2 && in; ++a) {
      const double dl = x(a) - (l.box.min()(a) - m), dh = (l.box.max()(a) + m) - x(a);
      const double d = std::min(dl, dh);
      in = d > 0.0;
      sign[a] = dl <= dh ? inv : -inv;
      s[a] = smoothstep(d * inv);
    }
    if (!in) continue;
    Cover c;
    c.leaf = i;
    c.w = s[0].s * s[1].s;
    if (!(c.w > 0.0)) continue;
    c.dw = Eigen::Vector2d(s[0].ds * sign[0] * s[1].s, s[0].s * s[1].ds * sign[1]);
    c.hw = Eigen::Vector3d(s[0].dds * inv * inv * s[1].s, s[0].ds * sign[0] * s[1].ds * sign[1],
                           s[0].s * s[1].dds * inv * inv);
    out.push_back(c);
  }
}

void LocalGpis::assign(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, std::vector<std::vector<Eigen::Index>>& cols,
                       std::vector<std::vector<double>>& weights) const {
  cols.assign(leaves_.size(), {});
  weights.assign(leaves_.size(), {});
  std::vector<Cover> cv;
  for (Eigen::Index j = 0; j < Q.cols(); ++j) {
    covers(Q.col(j), cv);
    for (const Cover& c : cv) {
      cols[c.leaf].push_back(j);
      weights[c.leaf].push_back(c.w);
    }
  }
}

namespace {
/// Sum of weights, weighted sums and the first local value per query; one
/// contributor: its value unchanged (the exact GP when one leaf holds all).
struct Blend {
  Eigen::VectorXd w, wm, wv, m1, v1;
  std::vector<int> count;
  explicit Blend(Eigen::Index n)
      : w(Eigen::VectorXd::Zero(n)), wm(Eigen::VectorXd::Zero(n)), wv(Eigen::VectorXd::Zero(n)),
        m1(Eigen::VectorXd::Zero(n)), v1(Eigen::VectorXd::Zero(n)), count(static_cast<std::size_t>(n), 0) {}
  void add(Eigen::Index j, double weight, double mean, double var) {
    if (count[static_cast<std::size_t>(j)]++ == 0) {
      m1(j) = mean;
      v1(j) = var;
    }
    w(j) += weight;
    wm(j) += weight * mean;
    wv(j) += weight * var;
  }
  double mean(Eigen::Index j) const {
    const int c = count[static_cast<std::size_t>(j)];
    return c == 0 ? kNaN : c == 1 ? m1(j) : wm(j) / w(j);
  }
  double var(Eigen::Index j) const {
    const int c = count[static_cast<std::size_t>(j)];
    return c == 0 ? kNaN : c == 1 ? v1(j) : wv(j) / w(j);
  }
};
}  // namespace

void LocalGpis::mean_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& mean) const {
  std::vector<std::vector<Eigen::Index>> cols;
  std::vector<std::vector<double>> weights;
  assign(Q, cols, weights);
  Blend b(Q.cols());
  Eigen::Matrix2Xd sub;
  Eigen::VectorXd m;
  for (std::size_t i = 0; i < leaves_.size(); ++i) {
    if (cols[i].empty()) continue;
    sub.resize(2, static_cast<Eigen::Index>(cols[i].size()));
    for (std::size_t k = 0; k < cols[i].size(); ++k) sub.col(static_cast<Eigen::Index>(k)) = Q.col(cols[i][k]);
    leaves_[i].gp->mean_batch(sub, m);  // 000 eq. 34 per local GP
    for (std::size_t k = 0; k < cols[i].size(); ++k) b.add(cols[i][k], weights[i][k], m(static_cast<Eigen::Index>(k)), 0.0);
  }
  mean.resize(Q.cols());
  for (Eigen::Index j = 0; j < Q.cols(); ++j) mean(j) = b.mean(j);
}

void LocalGpis::predict_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& mean,
                              Eigen::VectorXd& variance) const {
  std::vector<std::vector<Eigen::Index>> cols;
  std::vector<std::vector<double>> weights;
  assign(Q, cols, weights);
  Blend b(Q.cols());
  Eigen::Matrix2Xd sub;
  Eigen::VectorXd m, v;
  for (std::size_t i = 0; i < leaves_.size(); ++i) {
    if (cols[i].empty()) continue;
    sub.resize(2, static_cast<Eigen::Index>(cols[i].size()));
    for (std::size_t k = 0; k < cols[i].size(); ++k) sub.col(static_cast<Eigen::Index>(k)) = Q.col(cols[i][k]);
    leaves_[i].gp->predict_batch(sub, m, v);  // 000 eq. 34-35 per local GP
    for (std::size_t k = 0; k < cols[i].size(); ++k) {
      b.add(cols[i][k], weights[i][k], m(static_cast<Eigen::Index>(k)), v(static_cast<Eigen::Index>(k)));
    }
  }
  mean.resize(Q.cols());
  variance.resize(Q.cols());
  for (Eigen::Index j = 0; j < Q.cols(); ++j) {
    mean(j) = b.mean(j);
    variance(j) = b.var(j);
  }
}

void LocalGpis::derivatives(const Eigen::Vector2d& x, double* mean, Eigen::Vector2d* gradient,
                            Eigen::Matrix2d* hessian) const {
  std::vector<Cover> cv;
  covers(x, cv);
  if (cv.empty()) {
    if (mean) *mean = kNaN;
    if (gradient) gradient->setConstant(kNaN);
    if (hessian) hessian->setConstant(kNaN);
    return;
  }
  // f = N / W with N = sum w_j m_j, W = sum w_j:
  //   grad f = (grad N - f grad W) / W,
  //   H f = (H N - f H W - grad f grad W^T - grad W grad f^T) / W,
  //   grad N = sum (m_j grad w_j + w_j grad m_j),
  //   H N = sum (m_j H w_j + grad w_j grad m_j^T + grad m_j grad w_j^T + w_j H m_j),
  // with m_j, grad m_j, H m_j of local GP j (000 eq. 34, 36-39).
  double W = 0.0, N = 0.0;
  Eigen::Vector2d gW = Eigen::Vector2d::Zero(), gN = Eigen::Vector2d::Zero();
  Eigen::Matrix2d HW = Eigen::Matrix2d::Zero(), HN = Eigen::Matrix2d::Zero();
  for (const Cover& c : cv) {
    const Gpis& g = *leaves_[c.leaf].gp;
    const double mj = g.mean(x);
    Eigen::Vector2d gj;
    Eigen::Matrix2d Hj;
    g.derivatives(x, &gj, &Hj);
    Eigen::Matrix2d Hw;
    Hw << c.hw(0), c.hw(1), c.hw(1), c.hw(2);
    W += c.w;
    N += c.w * mj;
    gW += c.dw;
    gN += mj * c.dw + c.w * gj;
    HW += Hw;
    HN += mj * Hw + c.dw * gj.transpose() + gj * c.dw.transpose() + c.w * Hj;
  }
  const double f = N / W;
  const Eigen::Vector2d gf = (gN - f * gW) / W;
  if (mean) *mean = cv.size() == 1 ? leaves_[cv[0].leaf].gp->mean(x) : f;
  if (gradient) *gradient = gf;
  if (hessian) *hessian = (HN - f * HW - gf * gW.transpose() - gW * gf.transpose()) / W;
}

double LocalGpis::mean(const Eigen::Vector2d& x) const {
  Eigen::Matrix2Xd q = x;
  Eigen::VectorXd m;
  mean_batch(q, m);
  return m(0);
}

Eigen::Vector2d LocalGpis::gradient(const Eigen::Vector2d& x) const {
  Eigen::Vector2d g;
  derivatives(x, nullptr, &g, nullptr);
  return g;
}

void LocalGpis::curvature_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& kappa,
                                double min_gradient) const {
  kappa.resize(Q.cols());
  std::vector<Cover> cv;
  // Queries one leaf covers (weight 1 after normalisation): that local GP's
  // batched curvature; the others through the blended derivatives.
  std::vector<std::vector<Eigen::Index>> single(leaves_.size());
  for (Eigen::Index j = 0; j < Q.cols(); ++j) {
    covers(Q.col(j), cv);
    if (cv.empty()) {
      kappa(j) = kNaN;
    } else if (cv.size() == 1) {
      single[cv[0].leaf].push_back(j);
    } else {
      Eigen::Vector2d g;
      Eigen::Matrix2d H;
      derivatives(Q.col(j), nullptr, &g, &H);
      const double gn = g.norm();
      kappa(j) = (!(gn >= min_gradient) || gn == 0.0) ? kNaN
                                                        : (g.dot(H * g) - g.squaredNorm() * H.trace()) / (gn * gn * gn);  // 000 eq. 40
    }
  }
  Eigen::Matrix2Xd sub;
  Eigen::VectorXd k;
  for (std::size_t i = 0; i < leaves_.size(); ++i) {
    if (single[i].empty()) continue;
    sub.resize(2, static_cast<Eigen::Index>(single[i].size()));
    for (std::size_t s = 0; s < single[i].size(); ++s) sub.col(static_cast<Eigen::Index>(s)) = Q.col(single[i][s]);
    leaves_[i].gp->curvature_batch(sub, k, min_gradient);
    for (std::size_t s = 0; s < single[i].size(); ++s) kappa(single[i][s]) = k(static_cast<Eigen::Index>(s));
  }
}

std::size_t LocalGpis::largest_local() const {
  std::size_t n = 0;
  for (const auto& l : leaves_) n = std::max(n, l.members.size());
  return n;
}

std::size_t LocalGpis::state_bytes() const {
  std::size_t b = 0;
  for (const auto& l : leaves_) {
    const std::size_t n = l.members.size();
    b += sizeof(std::size_t) * (n + l.own.size()) + sizeof(double) * (5 * n + n * n);
  }
  return b;
}

}  // namespace gpis_explorer
