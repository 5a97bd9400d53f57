// How long one DDS sample takes from a writer in one process to a reader's listener in another,
// by how long both processes were idle before it (not a test; prints figures). A child process
// echoes every sample back; for each gap the parent writes a sample, waits for the echo, sleeps
// the gap, and so on. The hop is the reader's reception time less DDS's source timestamp (system
// clocks of one host), the same measure as the evaluator's estimate_hop_us_median. Run
// build/bin/dds_hop_benchmark [--gaps-us 1000,20000,100000] [--samples 100] [--domain 119];
// under `mrslam_launch --low-latency`'s request, hold /dev/cpu_dma_latency at 0 beside it.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "common/app.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"

namespace mrslam {
namespace {

using Type = msg::EstimatePubSubType;
using std::chrono::milliseconds;

struct Flags {
  std::vector<int> gaps_us = {1000, 20000, 100000};
  int samples = 100;
  int domain = 119;
};

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// An estimate of the size an agent of swarm_8 writes: 40 landmarks, 8 frames known.
msg::Estimate Sample() {
  msg::Estimate m;
  m.landmarks().resize(40);
  m.frames_known().resize(8, "robot_x");
  return m;
}

// One side: its participant, a writer on `out` and a reader on `in`, both matched.
struct Side {
  Side(int domain, const std::string& name, const std::string& out, const std::string& in)
      : participant({domain, name}), writer(participant, out), reader(participant, in) {
    while (writer.MatchedReaders() < 1 || reader.MatchedWriters() < 1) std::this_thread::sleep_for(milliseconds(10));
  }
  dds::Participant participant;
  dds::Writer<Type> writer;
  dds::Reader<Type> reader;
};

// The echoing child: sends every sample back until none comes for 5 s.
int Echo(int domain) {
  Side side(domain, "hop_echo", "mrslam/bench/pong", "mrslam/bench/ping");
  msg::Estimate m;
  while (side.reader.Take(&m, milliseconds(5000))) side.writer.Write(m);
  return 0;
}

int Measure(const Flags& flags) {
  Side side(flags.domain, "hop_bench", "mrslam/bench/ping", "mrslam/bench/pong");
  std::this_thread::sleep_for(milliseconds(300));  // both sides' discovery settled
  const msg::Estimate sample = Sample();
  std::printf("%10s %16s %16s\n", "gap_us", "hop_us_median", "round_trip_us");
  for (const int gap : flags.gaps_us) {
    std::vector<double> hops, trips;
    for (int i = 0; i < flags.samples; ++i) {
      std::this_thread::sleep_for(std::chrono::microseconds(gap));
      const auto start = std::chrono::steady_clock::now();
      side.writer.Write(sample);
      msg::Estimate echo;
      dds::SampleTimes times;
      if (!side.reader.Take(&echo, milliseconds(2000), nullptr, &times)) {
        std::fprintf(stderr, "dds_hop_benchmark: error: no echo within 2 s\n");
        return 1;
      }
      trips.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
      hops.push_back(static_cast<double>(times.received_ns - times.written_ns) / 1e3);
    }
    std::printf("%10d %16.0f %16.0f\n", gap, Median(hops), Median(trips));
  }
  return 0;
}

int Run(const Flags& flags) {
  const pid_t child = fork();  // before any DDS entity exists in this process
  if (child < 0) throw std::runtime_error("cannot fork the echoing process");
  if (child == 0) _exit(Echo(flags.domain));
  const int code = Measure(flags);
  int status = 0;
  waitpid(child, &status, 0);
  return code;
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
