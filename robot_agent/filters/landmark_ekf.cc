#include "robot_agent/filters/landmark_ekf.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <utility>

// The lane maths is always inlined into its kernels (see landmark_ekf.h): no vector argument
// crosses a call, whatever -Wpsabi reports at the end of this file.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace mrslam::robot_agent::filters {
namespace {

// One vector of kW lanes built from kW scalars, each read where it lies: a vector built from
// scalar loads, not from scalar stores to memory read back as one vector, which would stall on
// store forwarding.
template <typename T, std::size_t... L>
MRSLAM_LANE_INLINE T LoadLanes(const double* const* at, int offset, std::index_sequence<L...> /*lanes*/) {
  return T{at[L][offset]...};
}

// The update kernel over n queued updates, kW at a time: each lane's state is loaded from its
// block, updated, and stored back; lanes beyond n repeat the last update and are not stored. The
// state fields of the blocks kAhead updates on are requested in advance: the blocks of many
// particles do not all stay in cache between the filter's gating and here.
template <typename T, int D>
MRSLAM_LANE_INLINE void UpdateTargets(LandmarkBlock<D>* const* blocks, const int* lanes, const double* const* in, int n,
                                      double var_r, double var_b) {
  constexpr int kW = sizeof(T) / sizeof(double);
  constexpr int kState = D + TriangleSize(D);
  constexpr int kAhead = 16;
  for (int k = 0; k < n; k += kW) {
#pragma GCC unroll 16
    for (int l = 0; l < kW; ++l) {
      if (k + kAhead + l >= n) break;
#pragma GCC unroll 16
      for (int f = 0; f < kState; ++f) __builtin_prefetch(&blocks[k + kAhead + l]->field[f][0]);
    }
    double* at[kW];  // lane l's first field; field f lies f * kLanes further on
#pragma GCC unroll 16
    for (int l = 0; l < kW; ++l) {
      const int j = std::min(k + l, n - 1);
      at[l] = &blocks[j]->field[0][lanes[j]];
    }
    T state[kState], pose_z[5];
#pragma GCC unroll 16
    for (int f = 0; f < kState; ++f) state[f] = LoadLanes<T>(at, f * kLanes, std::make_index_sequence<kW>{});
#pragma GCC unroll 16
    for (int i = 0; i < 5; ++i) std::memcpy(&pose_z[i], in[i] + k, sizeof(T));
    EkfUpdate<T, D>(state, state + D, pose_z[0], pose_z[1], pose_z[2], pose_z[3], pose_z[4], var_r, var_b);
#pragma GCC unroll 16
    for (int l = 0; l < kW; ++l) {
      if (k + l >= n) break;
#pragma GCC unroll 16
      for (int f = 0; f < kState; ++f) at[l][f * kLanes] = state[f][l];
    }
  }
}

// The update kernel over whole blocks: field f of a block is one contiguous row of kLanes
// values, as is each of its inputs (UpdateBatch::WholeInputs); each row is loaded and stored kW
// lanes at a time. The fields of the blocks kAhead on are requested in advance.
template <typename T, int D>
MRSLAM_LANE_INLINE void UpdateWholeBlocks(LandmarkBlock<D>* const* blocks,
                                          const typename UpdateBatch<D>::WholeInputs* in, int n, double var_r,
                                          double var_b) {
  constexpr int kW = sizeof(T) / sizeof(double);
  constexpr int kState = D + TriangleSize(D);
  constexpr int kInputs = UpdateBatch<D>::kInputs;
  constexpr int kAhead = 2;
  for (int e = 0; e < n; ++e) {
    if (e + kAhead < n) {
#pragma GCC unroll 16
      for (int f = 0; f < kState; ++f) __builtin_prefetch(&blocks[e + kAhead]->field[f][0]);
    }
    LandmarkBlock<D>& block = *blocks[e];
#pragma GCC unroll 8
    for (int l = 0; l < kLanes; l += kW) {
      T state[kState], pose_z[kInputs];
#pragma GCC unroll 16
      for (int f = 0; f < kState; ++f) std::memcpy(&state[f], &block.field[f][l], sizeof(T));
#pragma GCC unroll 16
      for (int i = 0; i < kInputs; ++i) std::memcpy(&pose_z[i], &in[e].row[i][l], sizeof(T));
      EkfUpdate<T, D>(state, state + D, pose_z[0], pose_z[1], pose_z[2], pose_z[3], pose_z[4], var_r, var_b);
#pragma GCC unroll 16
      for (int f = 0; f < kState; ++f) std::memcpy(&block.field[f][l], &state[f], sizeof(T));
    }
  }
}

// What UpdateBatch::Run hands its kernel: n single lanes (blocks, lanes, input rows in) and
// whole_n whole blocks (whole, input rows whole_in).
template <int D>
struct QueuedUpdates {
  LandmarkBlock<D>* const* blocks;
  const int* lanes;
  const double* const* in;
  int n;
  LandmarkBlock<D>* const* whole;
  const typename UpdateBatch<D>::WholeInputs* whole_in;
  int whole_n;
  double var_r, var_b;
};

template <typename T, int D>
MRSLAM_LANE_INLINE void UpdateQueued(const QueuedUpdates<D>& q) {
  UpdateWholeBlocks<T, D>(q.whole, q.whole_in, q.whole_n, q.var_r, q.var_b);
  UpdateTargets<T, D>(q.blocks, q.lanes, q.in, q.n, q.var_r, q.var_b);
}

template <int D>
void UpdateQueuedSse2(const QueuedUpdates<D>& q) {
  UpdateQueued<Double2, D>(q);
}

#if defined(__x86_64__)
template <int D>
__attribute__((target("avx2"))) void UpdateQueuedAvx2(const QueuedUpdates<D>& q) {
  UpdateQueued<Double4, D>(q);
}
template <int D>
__attribute__((target("avx512f"))) void UpdateQueuedAvx512(const QueuedUpdates<D>& q) {
  UpdateQueued<Double8, D>(q);
}

// The widest vector unit of this CPU, found once.
enum class Simd { kSse2, kAvx2, kAvx512 };
Simd Widest() {
  static const Simd widest = __builtin_cpu_supports("avx512f") ? Simd::kAvx512
                             : __builtin_cpu_supports("avx2")  ? Simd::kAvx2
                                                               : Simd::kSse2;
  return widest;
}
#endif

}  // namespace

template <int D>
StateMatrix<D> MotionJacobian(const StateVector<D>& mean, double v_param, double w_param, double dt) {
  StateMatrix<D> f = StateMatrix<D>::Identity();
  if constexpr (D > 2) {
    const double v = D == 5 ? mean(3) : v_param;
    const double w = D == 5 ? mean(4) : w_param;
    const double c = std::cos(mean(2) + w * dt), s = std::sin(mean(2) + w * dt);
    f(0, 2) = -v * dt * s;
    f(1, 2) = v * dt * c;
    if constexpr (D == 5) {
      f(0, 3) = dt * c;
      f(1, 3) = dt * s;
      f(0, 4) = -v * dt * dt * s;
      f(1, 4) = v * dt * dt * c;
      f(2, 4) = dt;
    }
  }
  return f;
}

template <int D>
StateVector<D> MotionMean(const StateVector<D>& mean, double v_param, double w_param, double dt) {
  StateVector<D> out = mean;
  if constexpr (D > 2) {
    const double v = D == 5 ? mean(3) : v_param;
    const double w = D == 5 ? mean(4) : w_param;
    const double heading = mean(2) + w * dt;
    out(0) += v * dt * std::cos(heading);
    out(1) += v * dt * std::sin(heading);
    out(2) = common::WrapAngle(heading);
  }
  return out;
}

Eigen::Matrix2d MeasurementJacobianLandmark(const Eigen::Vector2d& landmark, const common::Pose2& pose) {
  const RangeBearingModel<double> m =
      PredictMeasurement(landmark.x(), landmark.y(), pose.x, pose.y, pose.heading, 0.0, 0.0);
  Eigen::Matrix2d h;
  h << m.a00, m.a01, m.a10, m.a11;
  return h;
}

Eigen::Matrix<double, 2, 3> MeasurementJacobianPose(const Eigen::Vector2d& landmark, const common::Pose2& pose) {
  Eigen::Matrix<double, 2, 3> h;
  h.leftCols<2>() = -MeasurementJacobianLandmark(landmark, pose);
  h.col(2) = Eigen::Vector2d(0.0, -1.0);
  return h;
}

template <int D>
StateVector<D> LandmarkBlock<D>::MeanVector(int lane) const {
  StateVector<D> m;
  for (int i = 0; i < D; ++i) m(i) = Mean(i, lane);
  return m;
}

template <int D>
StateMatrix<D> LandmarkBlock<D>::CovMatrix(int lane) const {
  StateMatrix<D> p;
  for (int i = 0; i < D; ++i) {
    for (int j = 0; j < D; ++j) p(i, j) = Cov(i, j, lane);
  }
  return p;
}

template <int D>
void LandmarkBlock<D>::Set(int lane, const StateVector<D>& mean, const StateMatrix<D>& cov) {
  for (int i = 0; i < D; ++i) {
    Mean(i, lane) = mean(i);
    for (int j = i; j < D; ++j) Cov(i, j, lane) = 0.5 * (cov(i, j) + cov(j, i));
  }
}

template <int D>
void LandmarkBlock<D>::CopyLane(int lane, LandmarkBlock* to, int to_lane) const {
  for (int f = 0; f < kFields; ++f) to->field[f][to_lane] = field[f][lane];
  to->meta[to_lane] = meta[lane];
}

namespace {

// PredictBlock's kernel, kW lanes at a time.
template <typename T, int D>
MRSLAM_LANE_INLINE void PredictLanes(LandmarkBlock<D>* block, int count, double dt, const double* q) {
  constexpr int kW = sizeof(T) / sizeof(double);
  constexpr int kTri = TriangleSize(D);
  for (int l = 0; l < count; l += kW) {
    T mean[D], cov[kTri];
#pragma GCC unroll 16
    for (int i = 0; i < D; ++i) std::memcpy(&mean[i], &block->field[i][l], sizeof(T));
#pragma GCC unroll 16
    for (int i = 0; i < kTri; ++i) std::memcpy(&cov[i], &block->field[D + i][l], sizeof(T));
    T v = Splat<T>(0.0), w = Splat<T>(0.0);
    if constexpr (D == 3) {
      std::memcpy(&v, &block->field[LandmarkBlock<D>::kParamV][l], sizeof(T));
      std::memcpy(&w, &block->field[LandmarkBlock<D>::kParamW][l], sizeof(T));
    }
    EkfPredict<T, D>(mean, cov, v, w, dt, q);
#pragma GCC unroll 16
    for (int i = 0; i < D; ++i) std::memcpy(&block->field[i][l], &mean[i], sizeof(T));
#pragma GCC unroll 16
    for (int i = 0; i < kTri; ++i) std::memcpy(&block->field[D + i][l], &cov[i], sizeof(T));
  }
}

template <int D>
void PredictLanesSse2(LandmarkBlock<D>* block, int count, double dt, const double* q) {
  PredictLanes<Double2, D>(block, count, dt, q);
}

#if defined(__x86_64__)
template <int D>
__attribute__((target("avx2"))) void PredictLanesAvx2(LandmarkBlock<D>* block, int count, double dt, const double* q) {
  PredictLanes<Double4, D>(block, count, dt, q);
}
template <int D>
__attribute__((target("avx512f"))) void PredictLanesAvx512(LandmarkBlock<D>* block, int count, double dt,
                                                           const double* q) {
  PredictLanes<Double8, D>(block, count, dt, q);
}
#endif

}  // namespace

template <int D>
void PredictBlock(LandmarkBlock<D>* block, int count, double dt, const double* q) {
#if defined(__x86_64__)
  switch (Widest()) {
    case Simd::kAvx512:
      return PredictLanesAvx512<D>(block, count, dt, q);
    case Simd::kAvx2:
      return PredictLanesAvx2<D>(block, count, dt, q);
    case Simd::kSse2:
      break;
  }
#endif
  PredictLanesSse2<D>(block, count, dt, q);
}

namespace {

// GateBlock's kernel, kW lanes at a time (count rounded up to kW: lanes are allocated in blocks
// of kLanes, a multiple of 8).
template <typename T, int D>
MRSLAM_LANE_INLINE void GateLanes(const LandmarkBlock<D>& block, int count, const common::Pose2& pose,
                                  const double* sigma, double z_r, double z_b, double var_r, double var_b,
                                  bool euclidean, double* d2) {
  constexpr int kW = sizeof(T) / sizeof(double);
  const T xr = Splat<T>(pose.x), yr = Splat<T>(pose.y), phi = Splat<T>(pose.heading);
  const T zr = Splat<T>(z_r), zb = Splat<T>(z_b);
  // sigma: (s00, s01, s11, s02, s12, s22) of the pose covariance.
  const double s00 = sigma[0], s01 = sigma[1], s11 = sigma[2];
  const double s02 = sigma[3], s12 = sigma[4], s22 = sigma[5];
  constexpr int k00 = D + Tri(0, 0, D), k01 = D + Tri(0, 1, D), k11 = D + Tri(1, 1, D);
  for (int l = 0; l < count; l += kW) {
    T lx, ly;
    std::memcpy(&lx, &block.field[0][l], sizeof(T));
    std::memcpy(&ly, &block.field[1][l], sizeof(T));
    const RangeBearingModel<T> m = PredictMeasurement(lx, ly, xr, yr, phi, zr, zb);
    T out;
    if (euclidean) {
      out = m.nu_r * m.nu_r + m.nu_b * m.nu_b;
    } else {
      // P' = P_pp + Sigma_pp; S = H_m P' H_m^T + R + pose-heading terms (see header).
      T p00, p01, p11;
      std::memcpy(&p00, &block.field[k00][l], sizeof(T));
      std::memcpy(&p01, &block.field[k01][l], sizeof(T));
      std::memcpy(&p11, &block.field[k11][l], sizeof(T));
      p00 = p00 + s00;
      p01 = p01 + s01;
      p11 = p11 + s11;
      const T g0 = m.a00 * s02 + m.a01 * s12;
      const T g1 = m.a10 * s02 + m.a11 * s12;
      const T a = m.a00 * p00 + m.a01 * p01, b = m.a00 * p01 + m.a01 * p11;  // row 0 of H P'
      const T c = m.a10 * p00 + m.a11 * p01, d = m.a10 * p01 + m.a11 * p11;  // row 1 of H P'
      const T s_rr = a * m.a00 + b * m.a01 + var_r;
      const T s_rb = a * m.a10 + b * m.a11 + g0;
      const T s_bb = c * m.a10 + d * m.a11 + var_b + 2.0 * g1 + s22;
      out = (s_bb * m.nu_r * m.nu_r - 2.0 * s_rb * m.nu_r * m.nu_b + s_rr * m.nu_b * m.nu_b) /
            (s_rr * s_bb - s_rb * s_rb);
    }
    std::memcpy(&d2[l], &out, sizeof(T));
  }
}

template <int D>
void GateLanesSse2(const LandmarkBlock<D>& block, int count, const common::Pose2& pose, const double* sigma, double z_r,
                   double z_b, double var_r, double var_b, bool euclidean, double* d2) {
  GateLanes<Double2, D>(block, count, pose, sigma, z_r, z_b, var_r, var_b, euclidean, d2);
}

#if defined(__x86_64__)
template <int D>
__attribute__((target("avx2"))) void GateLanesAvx2(const LandmarkBlock<D>& block, int count, const common::Pose2& pose,
                                                   const double* sigma, double z_r, double z_b, double var_r,
                                                   double var_b, bool euclidean, double* d2) {
  GateLanes<Double4, D>(block, count, pose, sigma, z_r, z_b, var_r, var_b, euclidean, d2);
}
template <int D>
__attribute__((target("avx512f"))) void GateLanesAvx512(const LandmarkBlock<D>& block, int count,
                                                        const common::Pose2& pose, const double* sigma, double z_r,
                                                        double z_b, double var_r, double var_b, bool euclidean,
                                                        double* d2) {
  GateLanes<Double8, D>(block, count, pose, sigma, z_r, z_b, var_r, var_b, euclidean, d2);
}
#endif

// GateLanes on the widest vector unit.
template <int D>
void GateLanesWidest(const LandmarkBlock<D>& block, int count, const common::Pose2& pose, const double* sigma,
                     double z_r, double z_b, double var_r, double var_b, bool euclidean, double* d2) {
#if defined(__x86_64__)
  switch (Widest()) {
    case Simd::kAvx512:
      return GateLanesAvx512<D>(block, count, pose, sigma, z_r, z_b, var_r, var_b, euclidean, d2);
    case Simd::kAvx2:
      return GateLanesAvx2<D>(block, count, pose, sigma, z_r, z_b, var_r, var_b, euclidean, d2);
    case Simd::kSse2:
      break;
  }
#endif
  GateLanesSse2<D>(block, count, pose, sigma, z_r, z_b, var_r, var_b, euclidean, d2);
}

}  // namespace

template <int D>
void GateBlock(const LandmarkBlock<D>& block, int count, const common::Pose2& pose, const Eigen::Matrix3d& pose_cov,
               double z_r, double z_b, double var_r, double var_b, bool euclidean, double* d2) {
  const double sigma[6] = {pose_cov(0, 0), pose_cov(0, 1), pose_cov(1, 1),
                           pose_cov(0, 2), pose_cov(1, 2), pose_cov(2, 2)};
  GateLanesWidest<D>(block, count, pose, sigma, z_r, z_b, var_r, var_b, euclidean, d2);
  for (int l = count; l < kLanes; ++l) d2[l] = std::numeric_limits<double>::infinity();
}

template <int D>
UpdateBatch<D>::UpdateBatch(double var_r, double var_b)
    : var_r_(var_r),
      var_b_(var_b),
      blocks_(kFlushSize),
      lanes_(kFlushSize),
      rows_(static_cast<std::size_t>(kInputs) * kRowStride),
      whole_(kFlushBlocks),
      whole_inputs_(kFlushBlocks) {}

template <int D>
void UpdateBatch<D>::SpillRun() {
  if (open_lanes_ == 0) return;
  const WholeInputs& open = whole_inputs_[whole_size_];
  for (int l = 0; l < open_lanes_; ++l) {
    AddSingle(whole_[whole_size_], l, {open.row[0][l], open.row[1][l], open.row[2][l]}, open.row[3][l], open.row[4][l]);
  }
  open_lanes_ = 0;
}

template <int D>
void UpdateBatch<D>::Run() {
  SpillRun();
  const int n = size_;
  // Input lanes up to a multiple of 8 repeat the last update (the kernels do not store them).
  const int padded = (n + 7) / 8 * 8;
  for (int k = n; k < padded; ++k) {
    for (int i = 0; i < kInputs; ++i) Input(i, k) = Input(i, n - 1);
  }
  const double* in[kInputs];
  for (int i = 0; i < kInputs; ++i) in[i] = &Input(i, 0);
  const QueuedUpdates<D> q{blocks_.data(),       lanes_.data(), in,     n,     whole_.data(),
                           whole_inputs_.data(), whole_size_,   var_r_, var_b_};
  size_ = 0;
  whole_size_ = 0;
#if defined(__x86_64__)
  switch (Widest()) {
    case Simd::kAvx512:
      return UpdateQueuedAvx512<D>(q);
    case Simd::kAvx2:
      return UpdateQueuedAvx2<D>(q);
    case Simd::kSse2:
      break;
  }
#endif
  UpdateQueuedSse2<D>(q);
}

#define MRSLAM_INSTANTIATE_EKF(D)                                                                                \
  template StateMatrix<D> MotionJacobian<D>(const StateVector<D>&, double, double, double);                      \
  template StateVector<D> MotionMean<D>(const StateVector<D>&, double, double, double);                          \
  template struct LandmarkBlock<D>;                                                                              \
  template void PredictBlock<D>(LandmarkBlock<D>*, int, double, const double*);                                  \
  template void GateBlock<D>(const LandmarkBlock<D>&, int, const common::Pose2&, const Eigen::Matrix3d&, double, \
                             double, double, double, bool, double*);                                             \
  template class UpdateBatch<D>;
MRSLAM_INSTANTIATE_EKF(2)
MRSLAM_INSTANTIATE_EKF(3)
MRSLAM_INSTANTIATE_EKF(5)
#undef MRSLAM_INSTANTIATE_EKF

}  // namespace mrslam::robot_agent::filters
