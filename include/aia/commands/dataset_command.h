// `aia dataset` (docs/learning.md, Dataset): the paper's recipe for
// imitation data. Episode e runs on the generated world of seed
// first_seed + e (runtime/generated.h, GeneratedScenario) with the acting
// policy (the expert; the learned policy for DAgger rounds), its beliefs fused
// by the DKF as in any mission; a shadow expert labels every robot's state with
// the expert's move from it (for the expert itself, its own moves); `keep`
// random decision steps of each episode are kept. Episodes are split over
// shards (e % shards == shard), each shard one SQLite file in the folder, one
// transaction per episode: a killed run resumes where it stopped and loses at
// most the episode in flight.
#ifndef AIA_COMMANDS_DATASET_COMMAND_H_
#define AIA_COMMANDS_DATASET_COMMAND_H_

#include <cstdint>
#include <string>
#include <vector>

#include "aia/core/field_values.h"
#include "aia/core/fields.h"

namespace aia {

struct DatasetOptions {
  std::string out;  // folder
  int episodes = 1500;
  Shard shard;                         // this process's episodes
  TeamSize size{10, 10};               // robots x targets
  std::uint64_t first_seed = 1000000;  // far from aia eval's seeds
  int keep = 10;                       // decision steps kept per episode
  std::string policy = "expert";       // the acting policy
  std::string model;                   // its model (igbnet)
  int max_steps = 0;                   // 0: the scenario's
  // An episode still running after this many seconds of wall time is
  // stopped and skipped: recorded as done with no samples, and counted
  // (0: no cap). Which episodes are skipped depends on the machine's speed.
  double max_seconds = 0.0;
  std::vector<std::string> sets;  // --set key=value
  bool progress = true;
  // For tests: once `stop_after_episodes` episodes were written, end the run
  // after 3 decisions of the next one without writing it, as a kill would
  // (-1: never).
  int stop_after_episodes = -1;

  // The flags, declared once for `aia dataset`'s flags and their checks
  // (core/fields.h; the policy and paths are checked apart).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(shard).Doc(
        "K/N: this process writes episodes e with e % N == K (under mpirun: "
        "the rank and the number of ranks)"));
    a->Visit(AIA_FIELD(size).Doc("robots x targets of the worlds"));
    a->Visit(AIA_FIELD(episodes)
                 .In(Between(1, 10000000))
                 .Doc("episodes in all shards"));
    a->Visit(AIA_FIELD(first_seed)
                 .Doc("episode e uses seed FIRST+e (aia eval uses 0..)"));
    a->Visit(AIA_FIELD(keep)
                 .In(Between(1, 100000))
                 .Doc("random decision steps kept per episode"));
    a->Visit(AIA_FIELD(max_steps)
                 .In(Between(0, 1000000))
                 .Doc("decision steps per episode at most (0: the "
                      "scenario's)"));
    a->Visit(AIA_FIELD(max_seconds)
                 .In(Between(0.0, 1e7))
                 .Doc("skip an episode still running after this many seconds "
                      "(recorded as done with no samples and counted; 0: no "
                      "cap)"));
  }
  // The seeds first_seed + e fit in 64 bits.
  void Validate(const FieldChecker& c) const;
};

// Returns the number of episodes written by this run.
int RunDataset(const DatasetOptions& options);

}  // namespace aia

#endif  // AIA_COMMANDS_DATASET_COMMAND_H_
