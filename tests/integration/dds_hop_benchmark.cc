// How long one DDS sample takes from a writer in one process to a reader's listener in another,
// by how long both processes were idle before it (not a test; prints figures). A child process
// echoes every sample back; for each gap the parent sleeps the gap, writes a sample and waits for
// the echo, and so on. A hop is the reader's reception time less DDS's source timestamp (system
// clocks of one host), the same measure as the evaluator's estimate_hop_us_median: the sample's
// after the gap, measured by the child and carried back in the echo, and the echo's, which
// follows at once. Run build/bin/dds_hop_benchmark [--gaps-us 1000,20000,100000] [--samples 100]
// [--domain 119]; `mrslam_launch --low-latency`'s request is /dev/cpu_dma_latency held at 0.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/app.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "world_sim/evaluator/metrics.h"

namespace mrslam {
namespace {

using Type = msg::EstimatePubSubType;
using std::chrono::milliseconds;

struct Flags {
  std::vector<int> gaps_us = {1000, 20000, 100000};
  int samples = 100;
  int domain = 119;
};

// An estimate of the size an agent of swarm_8 writes: 40 landmarks, 8 frames known.
msg::Estimate Sample() {
  msg::Estimate m;
  m.landmarks().resize(40);
  m.frames_known().resize(8, "robot_x");
  return m;
}

// One side: its participant, a writer on `out` and a reader on `in`, both matched within 10 s.
struct Side {
  Side(int domain, const std::string& name, const std::string& out, const std::string& in)
      : participant({domain, name}), writer(participant, out), reader(participant, in) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (writer.MatchedReaders() < 1 || reader.MatchedWriters() < 1) {
      if (std::chrono::steady_clock::now() > deadline) throw std::runtime_error("the other process did not match");
      std::this_thread::sleep_for(milliseconds(10));
    }
  }
  dds::Participant participant;
  dds::Writer<Type> writer;
  dds::Reader<Type> reader;
};

// The echoing child: sends every sample back, its hop in (microseconds) carried in the echo's
// step_cpu_ms field, until none comes for 5 s.
int Echo(int domain) {
  Side side(domain, "hop_echo", "mrslam/bench/pong", "mrslam/bench/ping");
  msg::Estimate m;
  dds::SampleTimes times;
  while (side.reader.Take(&m, milliseconds(5000), nullptr, &times)) {
    m.step_cpu_ms(times.HopUs());
    side.writer.Write(m);
  }
  return 0;
}

int Measure(const Flags& flags) {
  Side side(flags.domain, "hop_bench", "mrslam/bench/ping", "mrslam/bench/pong");
  std::this_thread::sleep_for(milliseconds(300));  // both sides' discovery settled
  const msg::Estimate sample = Sample();
  std::printf("%10s %16s %16s %16s\n", "gap_us", "hop_us_median", "hop_back_us", "round_trip_us");
  for (const int gap : flags.gaps_us) {
    std::vector<double> hops, backs, trips;
    for (int i = 0; i < flags.samples; ++i) {
      std::this_thread::sleep_for(std::chrono::microseconds(gap));
      const auto start = std::chrono::steady_clock::now();
      side.writer.Write(sample);
      msg::Estimate echo;
      dds::SampleTimes times;
      if (!side.reader.Take(&echo, milliseconds(2000), nullptr, &times)) {
        throw std::runtime_error("no echo within 2 s");
      }
      trips.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
      hops.push_back(echo.step_cpu_ms());
      backs.push_back(times.HopUs());
    }
    std::printf("%10d %16.0f %16.0f %16.0f\n", gap, evaluator::Median(hops), evaluator::Median(backs),
                evaluator::Median(trips));
  }
  return 0;
}

int Run(const Flags& flags) {
  const pid_t child = fork();  // before any DDS entity exists in this process
  if (child < 0) throw std::runtime_error("cannot fork the echoing process");
  if (child == 0) {
    try {
      _exit(Echo(flags.domain));
    } catch (...) {
      _exit(1);
    }
  }
  try {
    const int code = Measure(flags);
    waitpid(child, nullptr, 0);
    return code;
  } catch (...) {
    kill(child, SIGTERM);
    waitpid(child, nullptr, 0);
    throw;
  }
}

}  // namespace
}  // namespace mrslam

int main(int argc, char** argv) {
  mrslam::Flags flags;
  return mrslam::common::RunMain(
      "dds_hop_benchmark", "One DDS hop between two processes by how long they were idle before it", argc, argv,
      [&](CLI::App& app) {
        app.add_option("--gaps-us", flags.gaps_us, "Idle gaps before each sample, in microseconds")->delimiter(',');
        app.add_option("--samples", flags.samples, "Samples per gap")->check(CLI::Range(1, 100000));
        app.add_option("--domain", flags.domain, "DDS domain id")->check(CLI::Range(0, 232));
      },
      [&](const CLI::App&) { return mrslam::Run(flags); });
}
