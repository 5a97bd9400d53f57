// mrslam_batch: accuracy over many seeds, in-process (the World or a data set's replay, no DDS),
// as medians and 90th percentiles over the seeds, optionally with every seed's values as JSON;
// progress goes to stderr. Modes, each in its own file:
//   (default) each robot's own filter, scored per robot as the evaluator scores it
//     (docs/metrics.md): filter_accuracy;
//   --reference: the same with the approximately ideal filter (the oracle batch MAP smoother) in
//     place of each robot's own, on the same data (the lidar reports identities): filter_accuracy;
//     with --joint, the causal joint oracle: each robot's reference over its own data and what
//     the robots it met (directly or through others) held then: filter_accuracy, joint_oracle;
//     with --graph, the same with the agents' joint graph as the solver: joint_graph_oracle;
//   --transform-reference: per ordered pair of robots, the error of T(G_i <- G_j) at the end of
//     their first encounter as the joint MAP reference holds it: transform_reference;
//   --smoother: each robot's error under the MAP smoother of the whole run, jointly and alone, and
//     under the online yardstick alone (each pose from the data up to it): smoother_reference;
//   --slip-recovery: whether each robot's filter recovers from the scenario's slips:
//     slip_recovery;
//   --held DIR [--union]: each robot's error under the joint estimate over the raw measurements
//     its agent held at the end of a run (or all agents' together): held_reference.
//
//   mrslam_batch --scenario FILE --seeds A..B [--set k=v]... [--particles N] [--threads T]
//                [--reference [--joint [--graph]] | --transform-reference | --smoother | --slip-recovery |
//                 --held DIR [--union]]
//                [--every N] [--json FILE]
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "common/app.h"
#include "common/config/scenario_options.h"
#include "common/seed_range.h"
#include "scripts/batch/filter_accuracy.h"
#include "scripts/batch/held_reference.h"
#include "scripts/batch/slip_recovery.h"
#include "scripts/batch/smoother_reference.h"
#include "scripts/batch/transform_reference.h"

namespace mrslam::batch {
namespace {

int Main(int argc, char** argv) {
  CLI::App app{"Accuracy of each robot's own filter over seeds (in-process, no DDS)."};
  std::string scenario_path, seeds_text = "1..50", json_path, held_dir;
  std::vector<std::string> overrides;
  int particles = 0, threads = 1, every = 1;
  bool reference = false, joint = false, graph = false, transform_reference = false, smoother = false,
       slip_recovery = false, union_all = false;
  app.add_option("--scenario", scenario_path, "Scenario YAML file")->required();
  app.add_option("--seeds", seeds_text, "Seed range A..B (inclusive)");
  app.add_option("--set", overrides, "Override a scenario key: key.path=value (repeatable)");
  app.add_option("--particles", particles, "Particles per filter (overrides filter.particles)")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--threads", threads, "Seeds run in parallel")->check(CLI::Range(1, 256));
  auto* reference_flag =
      app.add_flag("--reference", reference,
                   "Run the approximately ideal reference instead of the filter: the batch MAP estimate of the "
                   "path so far at every step, with oracle association and landmark kinematics (static or "
                   "unicycle landmarks; with a landmark_field, its static landmarks)");
  app.add_flag("--joint", joint,
               "With --reference: the causal joint oracle, each robot's reference over its own data and, of "
               "every robot it met directly or through others, the data held at the last contact")
      ->needs(reference_flag);
  app.add_flag("--graph", graph,
               "With --reference --joint: the same bookkeeping with the agents' joint graph as the solver (robots "
               "placed by their mutual detections, odometry corrections estimated; poses only), solved to "
               "convergence from a cold start at every scored step (see --every)")
      ->needs("--joint");
  app.add_flag("--transform-reference", transform_reference,
               "Print instead the error of each pair's transform at the end of its first encounter as the "
               "joint MAP reference of both robots holds it");
  app.add_flag("--smoother", smoother,
               "Print instead each robot's error under the MAP smoother of the whole run: all robots' data "
               "jointly (only the first robot's start known) and each robot's data alone, and under the "
               "online yardstick of each robot alone (each pose from the data up to it)");
  app.add_flag("--slip-recovery", slip_recovery,
               "Print instead whether each slipping robot's filter recovers from its first slip (robots[].slips), "
               "against the same seed without the slips");
  auto* held_option =
      app.add_option("--held", held_dir,
                     "Print instead each robot's error under the joint estimate over the raw measurements its agent "
                     "held at the end of a run (DIR/<robot>.factors, robot_agent --factors-out; the run's scenario "
                     "and --seeds its seed)");
  app.add_flag("--union", union_all, "With --held: each robot's joint estimate over every agent's logs together")
      ->needs(held_option);
  app.add_option("--every", every,
                 "Score (and solve a reference) at every N-th step and the last only: the figures are over "
                 "those steps (for a long run's reference, and the filter's figures to set beside it)")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--json", json_path, "Write medians, 90th percentiles and per-seed values here");
  if (const auto status = common::ParseCommandLine("mrslam_batch", app, argc, argv)) return *status;

  const common::SeedRange seeds = common::ParseSeedRange("--seeds", seeds_text);
  common::ScenarioOptions options = common::LoadScenario(scenario_path, overrides);
  if (particles > 0) options.filter.particles = particles;
  if (static_cast<int>(reference) + static_cast<int>(transform_reference) + static_cast<int>(smoother) +
          static_cast<int>(slip_recovery) + static_cast<int>(!held_dir.empty()) >
      1) {
    throw std::runtime_error(
        "one of --reference, --transform-reference, --smoother, --slip-recovery and --held at most");
  }
  // The reference's oracle association: the same detections, with their identities.
  if (reference || transform_reference || smoother) options.sensors.lidar.report_identity = true;
  if (every > 1 && (transform_reference || smoother || slip_recovery || !held_dir.empty()))
    throw std::runtime_error("--every goes with the default mode and --reference [--joint] only");
  const auto first_seed = static_cast<std::uint64_t>(seeds.first);
  if (!held_dir.empty()) {
    options.seed = first_seed;
    return PrintHeldReference(options, held_dir, union_all, json_path);
  }
  if (transform_reference) return PrintTransformReference(options, first_seed, seeds.size(), threads, json_path);
  if (smoother) return PrintSmoother(options, first_seed, seeds.size(), threads, json_path);
  if (slip_recovery) return PrintSlipRecovery(options, first_seed, seeds.size(), threads, json_path);
  const Estimators estimators = graph   ? Estimators::kJointGraphReference
                                : joint ? Estimators::kJointReference
                                        : (reference ? Estimators::kReference : Estimators::kOwnFilter);
  return PrintFilterAccuracy(options, first_seed, seeds.size(), threads, json_path, estimators, every);
}

}  // namespace
}  // namespace mrslam::batch

int main(int argc, char** argv) {
  try {
    return mrslam::batch::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mrslam_batch: error: %s\n", e.what());
    return 1;
  }
}
