#include "robot_agent/filters/map_fusion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "common/angles.h"
#include "common/se2.h"

namespace mrslam::robot_agent::filters {

// Why covariance intersection is the default rule (scenario key cooperation.map_fusion): the
// peer's map and the own map are not independent. Both robots' transforms come from the same
// mutual detections and pose estimates; a peer's snapshot may already contain landmarks merged
// from this robot's earlier snapshots (maps spread through every encounter), and the peer's
// landmarks were estimated from its own pose track, whose error is shared by all of them. The
// cross-covariance is unknown, and information fusion (which assumes it zero) then counts the
// shared information twice and becomes overconfident with every repeated merge. Covariance
// intersection is consistent for any cross-covariance (its ellipse always contains the true
// one); it gives up some of the gain when the inputs really are independent.

MapLandmark TransformLandmark(const MapLandmark& in_peer, const common::Pose2& t_self_peer,
                              const Eigen::Matrix3d& t_covariance) {
  MapLandmark out = in_peer;
  const common::Pose2 l{in_peer.mean.x(), in_peer.mean.y(), in_peer.mean.z()};
  const common::Pose2 moved = common::Compose(t_self_peer, l);
  const Eigen::Matrix3d jt = common::ComposeJacobianLeft(t_self_peer, l);
  const Eigen::Matrix3d jl = common::ComposeJacobianRight(t_self_peer, l);
  out.mean = {moved.x, moved.y, moved.heading};
  const Eigen::Matrix3d c = jt * t_covariance * jt.transpose() + jl * in_peer.covariance * jl.transpose();
  out.covariance = 0.5 * (c + c.transpose());
  return out;
}

namespace {

template <int N>
using Vec = Eigen::Matrix<double, N, 1>;
template <int R, int C>
using Mat = Eigen::Matrix<double, R, C>;

// The gain-form update of FuseObservation with P0, R0 and K given; returns the fused covariance.
template <int N, int M>
Mat<N, N> JosephCovariance(const Mat<N, N>& p0, const Mat<M, M>& r0, const Mat<N, M>& k) {
  Mat<N, N> ikh = Mat<N, N>::Identity();
  ikh.template leftCols<M>() -= k;
  const Mat<N, N> p = ikh * p0 * ikh.transpose() + k * r0 * k.transpose();
  return 0.5 * (p + p.transpose());
}

// The Kalman gain K = P0 H^T (H P0 H^T + R0)^-1 for H = [I_M 0]; false if S is singular.
template <int N, int M>
bool KalmanGain(const Mat<N, N>& p0, const Mat<M, M>& r0, Mat<N, M>* k) {
  const Mat<M, M> s = p0.template topLeftCorner<M, M>() + r0;
  const Eigen::LLT<Mat<M, M>> llt(s);
  if (llt.info() != Eigen::Success) return false;
  // K^T = S^-1 (P0 H^T)^T.
  *k = llt.solve(p0.template leftCols<M>().transpose()).transpose();
  return k->allFinite();
}

// g(omega) of CovarianceIntersectionWeight and its first two derivatives.
template <int M>
struct CiObjective {
  Vec<M> lambda;
  int extra;  // n - M
  double Value(double omega) const {
    double g = extra > 0 ? extra * std::log(omega) : 0.0;
    for (int i = 0; i < M; ++i) g += std::log(lambda(i) + omega * (1.0 - lambda(i)));
    return g;
  }
  double Slope(double omega) const {
    double d = extra / omega;
    for (int i = 0; i < M; ++i) d += (1.0 - lambda(i)) / (lambda(i) + omega * (1.0 - lambda(i)));
    return d;
  }
  double Curvature(double omega) const {
    double c = -extra / (omega * omega);
    for (int i = 0; i < M; ++i) {
      const double q = (1.0 - lambda(i)) / (lambda(i) + omega * (1.0 - lambda(i)));
      c -= q * q;
    }
    return c;
  }
};

// The root of the decreasing g' in (lo, hi), given g'(lo) > 0 > g'(hi): Newton steps, each kept
// inside the bracket that the sign of g' maintains (else the bracket's midpoint).
template <int M>
double SlopeRoot(const CiObjective<M>& g, double lo, double hi) {
  constexpr double kTolerance = 1e-12;
  constexpr int kMaxIterations = 100;
  double omega = 0.5 * (lo + hi);
  for (int i = 0; i < kMaxIterations && hi - lo > kTolerance; ++i) {
    const double slope = g.Slope(omega);
    (slope > 0.0 ? lo : hi) = omega;
    double next = omega - slope / g.Curvature(omega);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool converged = std::abs(next - omega) <= kTolerance;
    omega = next;
    if (converged) break;
  }
  return omega;
}

}  // namespace

template <int M>
std::optional<double> CovarianceIntersectionWeight(const Mat<M, M>& p_mm, const Mat<M, M>& r, int n) {
  const Eigen::LLT<Mat<M, M>> llt(r);
  if (llt.info() != Eigen::Success || !p_mm.allFinite()) return std::nullopt;
  const Mat<M, M> half = llt.matrixL().solve(p_mm);           // L^-1 p_mm
  const Mat<M, M> c = llt.matrixL().solve(half.transpose());  // L^-1 p_mm L^-T
  const Eigen::SelfAdjointEigenSolver<Mat<M, M>> es(0.5 * (c + c.transpose()), Eigen::EigenvaluesOnly);
  if (es.info() != Eigen::Success || !(es.eigenvalues().minCoeff() > 0.0)) return std::nullopt;
  const CiObjective<M> g{es.eigenvalues(), n - M};
  constexpr double kLo = 1e-4, kHi = 1.0 - 1e-4;
  double omega = kLo;
  if (g.Slope(kHi) >= 0.0) {
    omega = kHi;
  } else if (g.Slope(kLo) > 0.0) {
    omega = SlopeRoot(g, kLo, kHi);
  }
  const double fused = g.Value(omega);
  const double keep = 0.0;  // g(1)
  const double take = n == M ? g.Value(0.0) : -std::numeric_limits<double>::infinity();
  if (keep >= fused && keep >= take) return 1.0;
  if (take > fused) return 0.0;
  return omega;
}

template <int N, int M>
bool FuseObservation(Vec<N>* x, Mat<N, N>* p, const Vec<M>& z, const Mat<M, M>& r, MapFusionRule rule,
                     int angle_index) {
  static_assert(M >= 1 && M <= N, "the observed components are the state's first M");
  if (!x->allFinite() || !p->allFinite() || !z.allFinite() || !r.allFinite()) return false;
  Vec<M> nu = z - x->template head<M>();
  if (angle_index >= 0 && angle_index < M) nu(angle_index) = common::WrapAngle(nu(angle_index));

  Mat<N, M> k = Mat<N, M>::Zero();
  Mat<N, N> p_new = *p;
  switch (rule) {
    case MapFusionRule::kAverage: {
      k.template topRows<M>() = 0.5 * Mat<M, M>::Identity();
      p_new = JosephCovariance<N, M>(*p, r, k);
      break;
    }
    case MapFusionRule::kWeighted: {
      if (!KalmanGain<N, M>(*p, r, &k)) return false;
      p_new = JosephCovariance<N, M>(*p, r, k);
      break;
    }
    case MapFusionRule::kCovarianceIntersection: {
      const std::optional<double> omega = CovarianceIntersectionWeight<M>(p->template topLeftCorner<M, M>(), r, N);
      if (!omega) return false;
      if (*omega == 1.0) return true;  // keep the own estimate: unchanged
      if constexpr (N == M) {
        if (*omega == 0.0) {  // take the incoming one
          k.setIdentity();
          p_new = r;
          break;
        }
      }
      const Mat<N, N> p0 = *p / *omega;
      const Mat<M, M> r0 = r / (1.0 - *omega);
      if (!KalmanGain<N, M>(p0, r0, &k)) return false;
      p_new = JosephCovariance<N, M>(p0, r0, k);
      break;
    }
  }
  if (!p_new.allFinite()) return false;
  *x += k * nu;
  if (angle_index >= 0 && angle_index < N) (*x)(angle_index) = common::WrapAngle((*x)(angle_index));
  *p = p_new;
  return true;
}

template std::optional<double> CovarianceIntersectionWeight<2>(const Mat<2, 2>&, const Mat<2, 2>&, int);
template std::optional<double> CovarianceIntersectionWeight<3>(const Mat<3, 3>&, const Mat<3, 3>&, int);
template bool FuseObservation<2, 2>(Vec<2>*, Mat<2, 2>*, const Vec<2>&, const Mat<2, 2>&, MapFusionRule, int);
template bool FuseObservation<3, 2>(Vec<3>*, Mat<3, 3>*, const Vec<2>&, const Mat<2, 2>&, MapFusionRule, int);
template bool FuseObservation<3, 3>(Vec<3>*, Mat<3, 3>*, const Vec<3>&, const Mat<3, 3>&, MapFusionRule, int);
template bool FuseObservation<5, 2>(Vec<5>*, Mat<5, 5>*, const Vec<2>&, const Mat<2, 2>&, MapFusionRule, int);
template bool FuseObservation<5, 3>(Vec<5>*, Mat<5, 5>*, const Vec<3>&, const Mat<3, 3>&, MapFusionRule, int);

std::int64_t OriginKey(int origin_robot, std::uint32_t origin_track) {
  return origin_robot < 0 ? -1 : (static_cast<std::int64_t>(origin_robot) << 32) | origin_track;
}

MatchCandidate CandidateOf(const MapLandmark& l) {
  return {l.mean.head<2>(), l.covariance.topLeftCorner<2, 2>(), l.landmark_id,
          OriginKey(l.origin_robot, l.origin_track), !l.moving};
}

namespace {

// The own candidates by position, identity and provenance, so that an incoming landmark meets
// only those it can pair with: a pair by position needs |d| < too_close_m or d2 <= gate_d2, and
// d2 = d' S^-1 d >= |d|^2 / tr(S) where det S > 0 and tr S >= 0 (S is then positive definite;
// d2 is computed only where det S > 0), so no own landmark farther than
// max(too_close_m, sqrt(gate_d2 (tr(S_in) + max tr(S_own)))) in x can pair by position.
class OwnIndex {
 public:
  explicit OwnIndex(const std::vector<MatchCandidate>& own) {
    for (int j = 0; j < static_cast<int>(own.size()); ++j) {
      const MatchCandidate& o = own[j];
      if (o.landmark_id >= 0) by_id_.emplace_back(o.landmark_id, j);
      if (o.origin >= 0) by_origin_.emplace_back(o.origin, j);
      // A position that is not finite pairs with nothing by position (d is not a number).
      if (!o.position.allFinite()) continue;
      by_x_.emplace_back(o.position.x(), j);
      // A covariance that is not finite or has a negative trace leaves the bound unproven.
      const double trace = o.covariance.allFinite() ? o.covariance.trace() : -1.0;
      max_trace_ = std::max(max_trace_, trace);
      min_trace_ = std::min(min_trace_, trace);
    }
    std::sort(by_id_.begin(), by_id_.end());
    std::sort(by_origin_.begin(), by_origin_.end());
    std::sort(by_x_.begin(), by_x_.end());
  }

  // Calls fn(j) for every own j with this identity or provenance.
  template <typename Fn>
  void ForEachWithId(std::int64_t id, Fn&& fn) const {
    ForEachWithKey(by_id_, id, fn);
  }
  template <typename Fn>
  void ForEachWithOrigin(std::int64_t origin, Fn&& fn) const {
    ForEachWithKey(by_origin_, origin, fn);
  }

  // Calls fn(j) for every own j that may pair with `in` by position (a superset: at most the
  // x-window that the bound above allows; every own landmark if the bound does not hold).
  template <typename Fn>
  void ForEachNear(const MatchCandidate& in, double gate_d2, double too_close_m, Fn&& fn) const {
    if (!in.position.allFinite()) return;
    constexpr double kSlack = 1.0 + 1e-6;  // the d2 computation's rounding
    const double in_trace = in.covariance.allFinite() ? in.covariance.trace() : -1.0;
    double reach = std::numeric_limits<double>::infinity();
    if (in_trace >= 0.0 && min_trace_ >= 0.0) {
      reach = std::max(too_close_m, std::sqrt(gate_d2 * (in_trace + max_trace_)) * kSlack);
    }
    const double x = in.position.x();
    auto it = std::lower_bound(by_x_.begin(), by_x_.end(), std::make_pair(x - reach, -1));
    for (; it != by_x_.end() && it->first <= x + reach; ++it) fn(it->second);
  }

 private:
  using Keyed = std::vector<std::pair<std::int64_t, int>>;  // (key, own index), sorted
  template <typename Fn>
  static void ForEachWithKey(const Keyed& keyed, std::int64_t key, Fn&& fn) {
    auto it = std::lower_bound(keyed.begin(), keyed.end(), std::make_pair(key, -1));
    for (; it != keyed.end() && it->first == key; ++it) fn(it->second);
  }

  Keyed by_id_;
  Keyed by_origin_;
  std::vector<std::pair<double, int>> by_x_;
  double max_trace_ = 0.0;
  double min_trace_ = 0.0;
};

}  // namespace

std::vector<int> MatchLandmarks(const std::vector<MatchCandidate>& own, const std::vector<MatchCandidate>& incoming,
                                double gate_d2, double too_close_m) {
  // (distance, incoming, own); identity matches get distance -1 so that they come first.
  std::vector<std::tuple<double, int, int>> pairs;
  std::vector<char> near(incoming.size(), 0);  // static, within too_close_m of a static own one
  const OwnIndex index(own);
  for (int i = 0; i < static_cast<int>(incoming.size()); ++i) {
    const MatchCandidate& in = incoming[i];
    // Both with identities: equal ones match, no other pairing. Else equal provenance matches.
    if (in.landmark_id >= 0) index.ForEachWithId(in.landmark_id, [&](int j) { pairs.emplace_back(-1.0, i, j); });
    if (in.origin >= 0) {
      index.ForEachWithOrigin(in.origin, [&](int j) {
        if (in.landmark_id < 0 || own[j].landmark_id < 0) pairs.emplace_back(-1.0, i, j);
      });
    }
    index.ForEachNear(in, gate_d2, too_close_m, [&](int j) {
      const MatchCandidate& o = own[j];
      if (in.landmark_id >= 0 && o.landmark_id >= 0) return;
      if (in.origin >= 0 && in.origin == o.origin) return;
      const Eigen::Vector2d d = in.position - o.position;
      if (in.stationary && o.stationary && d.norm() < too_close_m) near[i] = 1;
      const Eigen::Matrix2d s = in.covariance + o.covariance;
      const double det = s(0, 0) * s(1, 1) - s(0, 1) * s(1, 0);
      if (!(det > 0.0)) return;
      const double d2 = (s(1, 1) * d.x() * d.x() - 2.0 * s(0, 1) * d.x() * d.y() + s(0, 0) * d.y() * d.y()) / det;
      if (d2 <= gate_d2) pairs.emplace_back(d2, i, j);
    });
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int> match(incoming.size(), -1);
  std::vector<char> own_used(own.size(), 0);
  for (const auto& [d2, i, j] : pairs) {
    if (match[i] >= 0 || own_used[j]) continue;
    match[i] = j;
    own_used[j] = 1;
  }
  for (std::size_t i = 0; i < incoming.size(); ++i) {
    if (match[i] < 0 && near[i] && incoming[i].landmark_id < 0) match[i] = kTooClose;
  }
  return match;
}

}  // namespace mrslam::robot_agent::filters
