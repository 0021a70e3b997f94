// The imitation dataset (docs/learning.md, Dataset): states, not images. One
// SQLite file per shard, readable from Python's standard library
// (tools/igbnet.py). Each episode (its world and its kept samples) is
// written in one transaction, so a killed writer loses at most the episode
// in flight and a resumed one skips what is done. No torch here.
#ifndef AIA_LEARNING_DATASET_H_
#define AIA_LEARNING_DATASET_H_

#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "aia/core/geometry.h"
#include "aia/core/types.h"
#include "aia/estimation/heatmap.h"
#include "aia/learning/channels.h"

namespace aia {

class Lattice;

// Version 2 adds each sample's search points, version 3 the robot's last
// lattice move (older files read with none).
inline constexpr int kDatasetFormatVersion = 3;

// One episode's world: what the map is rebuilt from, and its outcome.
struct DatasetWorld {
  std::int64_t episode = 0;  // unique within a dataset folder
  std::int64_t seed = 0;     // the scenario's seed for this episode
  Vec2 size{20.0, 20.0};     // workspace, metres
  double map_cell = 0.1;     // occupancy cell
  double lattice_step = 0.5;
  double robot_radius = 0.15;
  double eps = 0.1;
  int robots = 0;
  int targets = 0;
  int steps = 0;      // decision steps the episode ran
  int flowtime = -1;  // -1: no success
  std::vector<Box> obstacles;
  std::vector<double> log_det_prior;  // per target
};

// One robot at one decision step.
struct DatasetSample {
  std::int64_t episode = 0;
  int step = 0;
  int robot = 0;
  Vec2 position{0.0, 0.0};
  std::vector<Vec2> neighbours;     // this step's neighbours' positions
  std::vector<HeatSource> targets;  // the robot's own fused belief
  // Per target, the robot's search points (planning/search.h, SearchPoints;
  // empty: the mean); empty: none anywhere.
  std::vector<std::vector<Vec2>> search;
  Move label = Move::kStay;  // the expert's move from this state
  bool useful = true;  // the robot still had useful work in the expert's plan
  Move acted = Move::kStay;  // what the acting policy did
  // The robot's last lattice move before this step (kStay: none yet).
  Move came = Move::kStay;
  int world = -1;  // index into Dataset::worlds (set when read)
};

// What sample `s` of world `w` remembers, for the channels that show it
// (learning/channels.h, RobotMemory; the trail from its last move and the
// world's lattice step). Points into `s`.
RobotMemory SampleMemory(const DatasetSample& s, const DatasetWorld& w);

struct Dataset {
  std::vector<DatasetWorld> worlds;    // by (file, episode)
  std::vector<DatasetSample> samples;  // by (world, step, robot)
};

class DatasetWriter {
 public:
  // Opens or creates the SQLite file `path`. `recipe` describes how the
  // episodes are made; a file written with another recipe is refused
  // (InputError naming `key`).
  DatasetWriter(const std::string& path, const std::string& recipe,
                const std::string& key);
  ~DatasetWriter();
  DatasetWriter(const DatasetWriter&) = delete;
  DatasetWriter& operator=(const DatasetWriter&) = delete;

  // Episodes already written.
  const std::set<std::int64_t>& done() const { return done_; }
  // The world and its samples, in one transaction. A write the file system
  // refuses (a full disk) throws std::runtime_error("cannot write 'PATH':
  // <errno text>").
  void WriteEpisode(const DatasetWorld& world,
                    const std::vector<DatasetSample>& samples);

 private:
  struct Db;
  std::unique_ptr<Db> db_;
  std::string path_;
  std::set<std::int64_t> done_;
};

// N of a shard file named "shard-K-of-N.sqlite" (aia dataset --shard K/N),
// 0 for any other name.
int ShardCount(const std::string& path);

// The options a dataset file was written with (aia dataset's recipe), read
// alone; "" for a file that holds none yet. InputError naming `key` for a
// file that is not a dataset.
std::string DatasetRecipe(const std::string& path, const std::string& key);

// The files `paths` name: each file given, and every `*.sqlite` file of
// each folder, sorted by name. InputError naming `key` for a missing path, a
// folder without dataset files, a folder that mixes shard sets of different
// counts (shard-K-of-N.sqlite with two N) or shards of one set written with
// other options (recipes), and a file read twice (given twice, through a
// link, or as a file and within its folder).
std::vector<std::string> DatasetFiles(const std::vector<std::string>& paths,
                                      const std::string& key);

// Reads DatasetFiles(paths, key). A file that is not a dataset of this
// format, or an episode found in two files with the same recipe (a copy;
// shard sets of two counts), is an InputError naming `key`.
Dataset ReadDataset(const std::vector<std::string>& paths,
                    const std::string& key);

// The indices of each world's samples: result[w] holds worlds[w]'s, in
// sample order.
std::vector<std::vector<int>> SamplesByWorld(const Dataset& d);

// The moves valid from the lattice point nearest `position` (bit m: Move
// m), the moves the igbnet policy chooses among there (Lattice::Valid).
std::uint8_t ValidMoveBits(const Lattice& lattice, const Vec2& position);

}  // namespace aia

#endif  // AIA_LEARNING_DATASET_H_
