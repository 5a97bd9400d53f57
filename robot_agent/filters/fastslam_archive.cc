#include <cstdint>
#include <map>
#include <memory>
#include <type_traits>
#include <vector>

#include "robot_agent/filters/fastslam.h"

namespace mrslam::robot_agent::filters {

template <int D>
void FastSlam<D>::Io(common::Archive& ar) {
  ar(rng_, log_weights_, last_ess_, pose_, pose_covariance_, step_, time_s_, imu_step_, imu_speed_change_,
     imu_speed_var_, calibration_, next_track_id_, creation_ids_, detection_labels_, detection_tracks_);
  IoParticles(ar);
  if (ar.loading()) map_estimate_.value.reset();  // a cache of the particles it held before
}

// The distinct landmark blocks first, each once, then per particle its pose, speed, landmark
// count and the indices of its blocks among them: copy-on-write sharing survives the trip.
template <int D>
void FastSlam<D>::IoParticles(common::Archive& ar) {
  static_assert(std::is_trivially_copyable_v<Block>);
  std::vector<std::shared_ptr<Block>> blocks;
  std::map<const Block*, std::uint32_t> index;
  for (const Particle& p : particles_) {
    for (const auto& b : p.blocks) {
      if (index.emplace(b.get(), static_cast<std::uint32_t>(blocks.size())).second) blocks.push_back(b);
    }
  }
  const std::size_t n_blocks = ar.Count(blocks.size(), sizeof(Block));
  if (ar.loading()) {
    blocks.clear();
    for (std::size_t i = 0; i < n_blocks; ++i) blocks.push_back(std::make_shared<Block>());
  }
  for (auto& b : blocks) ar.Raw(b.get(), sizeof(Block));
  const std::size_t n_particles = ar.Count(particles_.size(), sizeof(common::Pose2));
  if (ar.loading()) particles_.assign(n_particles, Particle());
  for (Particle& p : particles_) {
    std::vector<std::uint32_t> indices;
    for (const auto& b : p.blocks) indices.push_back(index.at(b.get()));
    ar(p.pose, p.speed_mps, p.count, indices);
    if (!ar.loading()) continue;
    p.blocks.clear();
    for (const std::uint32_t i : indices) {
      if (i >= blocks.size())
        throw common::ArchiveError("archive: a particle names a landmark block that is not there");
      p.blocks.push_back(blocks[i]);
    }
    if (p.count < 0 || p.count > static_cast<int>(p.blocks.size()) * kLanes) {
      throw common::ArchiveError("archive: a particle holds more landmarks than its blocks");
    }
    if constexpr (D == 5) GatherStationary(&p);  // finds where the static landmarks end
  }
  if (ar.loading() && log_weights_.size() != particles_.size()) {
    throw common::ArchiveError("archive: particles and weights differ in number");
  }
}

template void FastSlam<2>::Io(common::Archive& ar);
template void FastSlam<3>::Io(common::Archive& ar);
template void FastSlam<5>::Io(common::Archive& ar);

}  // namespace mrslam::robot_agent::filters
