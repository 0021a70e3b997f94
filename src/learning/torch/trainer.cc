#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <numeric>
#include <sstream>
#include <thread>

#include "aia/core/clock.h"
#include "aia/core/error.h"
#include "aia/core/field_io.h"
#include "aia/core/hash.h"
#include "aia/core/io.h"
#include "aia/core/progress.h"
#include "aia/core/rng.h"
#include "aia/learning/dataset.h"
#include "aia/world/map.h"
#include "archive.h"
#include "torch_net.h"

// jemalloc's control: build/aia links jemalloc (tools/aia_main.cc); weak, so
// that a process without it (Python, the sanitizer tree) leaves its
// allocator alone.
extern "C" int mallctl(const char* name, void* oldp, std::size_t* oldlenp,
                       void* newp, std::size_t newlen) __attribute__((weak));

namespace aia {
namespace {

using Clock = std::chrono::steady_clock;

// The dataset with one channel renderer per world.
struct Corpus {
  Dataset data;
  std::vector<ChannelRenderer> renderers;
  std::vector<char> val_world;
  std::vector<int> train, val;  // sample indices
  // Per sample, ValidMoveBits (dataset.h): filled for a loss among the
  // valid moves (TrainOptions::valid_moves), else empty.
  std::vector<std::uint8_t> valid;
  // For message passing: each sample's neighbours among the samples of its
  // world and step (matched by position; a neighbour the dataset holds no
  // sample of, one the expert kept still, is left out).
  std::vector<std::vector<int>> neighbours;
};

// Whether samples a and b are robots of the same world at the same step.
bool SameStep(const Corpus& c, int a, int b) {
  const DatasetSample &x = c.data.samples[a], &y = c.data.samples[b];
  return x.world == y.world && x.step == y.step;
}

// Fills c->neighbours (samples come sorted by world, step and robot).
void LinkNeighbours(Corpus* c) {
  const std::vector<DatasetSample>& s = c->data.samples;
  const int n = static_cast<int>(s.size());
  c->neighbours.assign(n, {});
  std::map<std::pair<double, double>, int> at;
  for (int b = 0; b < n;) {
    int e = b;
    while (e < n && SameStep(*c, e, b)) ++e;
    at.clear();
    for (int i = b; i < e; ++i)
      at.emplace(std::make_pair(s[i].position.x(), s[i].position.y()), i);
    for (int i = b; i < e; ++i)
      for (const Vec2& p : s[i].neighbours) {
        const auto it = at.find({p.x(), p.y()});
        if (it != at.end() && it->second != i)
          c->neighbours[i].push_back(it->second);
      }
    b = e;
  }
}

// The rows a batch of `centres` renders: the centres first, then every
// sample within `hops` links of one (their outputs need them), and the
// graph among those rows.
void GraphRows(const Corpus& c, const std::vector<int>& centres, int hops,
               std::vector<int>* rows, TeamGraph* graph) {
  *rows = centres;
  std::map<int, int> row_of;
  for (int b = 0; b < static_cast<int>(centres.size()); ++b)
    row_of.emplace(centres[b], b);
  std::size_t frontier = 0;
  for (int k = 0; k < hops; ++k) {
    const std::size_t end = rows->size();
    for (std::size_t r = frontier; r < end; ++r)
      for (int j : c.neighbours[(*rows)[r]])
        if (row_of.emplace(j, static_cast<int>(rows->size())).second)
          rows->push_back(j);
    frontier = end;
  }
  graph->offsets.assign(1, 0);
  graph->neighbours.clear();
  for (int i : *rows) {
    for (int j : c.neighbours[i]) {
      const auto it = row_of.find(j);
      if (it != row_of.end()) graph->neighbours.push_back(it->second);
    }
    graph->offsets.push_back(static_cast<int>(graph->neighbours.size()));
  }
}

// The batches of one pass over `samples` (in this order) for message
// passing: whole steps, each batch the samples of consecutive steps until it
// holds `batch` or more. `samples` must list each step's samples together.
std::vector<std::vector<int>> StepBatches(const Corpus& c,
                                          const std::vector<int>& samples,
                                          int batch) {
  std::vector<std::vector<int>> out(1);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    out.back().push_back(samples[i]);
    const bool step_ends =
        i + 1 == samples.size() || !SameStep(c, samples[i + 1], samples[i]);
    if (step_ends && static_cast<int>(out.back().size()) >= batch &&
        i + 1 < samples.size())
      out.emplace_back();
  }
  if (out.back().empty()) out.pop_back();
  return out;
}

Corpus LoadCorpus(const std::vector<std::string>& paths,
                  const ChannelParams& channels, double val_share,
                  std::uint64_t seed, double weak_weight, bool valid_moves) {
  Corpus c;
  c.data = ReadDataset(paths, "--data");
  if (c.data.samples.empty())
    throw InputError::Flag("--data", "holds no samples");
  c.renderers.reserve(c.data.worlds.size());
  std::vector<std::vector<int>> of_world;
  if (valid_moves) {
    of_world = SamplesByWorld(c.data);
    c.valid.resize(c.data.samples.size());
  }
  for (std::size_t wi = 0; wi < c.data.worlds.size(); ++wi) {
    const DatasetWorld& w = c.data.worlds[wi];
    const ChannelParams at_step = AtLatticeStep(channels, w.lattice_step);
    if (const std::string why = ChannelGridProblem(w.size, at_step);
        !why.empty())
      throw InputError::Flag(
          "--data",
          "world of episode " + std::to_string(w.episode) + ": " + why);
    const Map map(w.size, w.obstacles, w.map_cell, w.lattice_step,
                  w.robot_radius);
    c.renderers.emplace_back(map.occupancy(), w.size, at_step, &map.lattice());
    if (valid_moves)
      for (int i : of_world[wi])
        c.valid[i] = ValidMoveBits(map.lattice(), c.data.samples[i].position);
    // The split is by world: a world's samples all go one way.
    Rng rng(seed, "train/split", static_cast<std::uint64_t>(w.seed));
    c.val_world.push_back(rng.Uniform() < val_share ? 1 : 0);
  }
  for (int i = 0; i < static_cast<int>(c.data.samples.size()); ++i) {
    const DatasetSample& s = c.data.samples[i];
    if (c.val_world[s.world]) {
      c.val.push_back(i);
    } else if (s.useful || weak_weight > 0.0) {
      c.train.push_back(i);
    }
  }
  return c;
}

// Targets a robot's own belief holds above eps, at most, for a sample to be
// of a mission's ending (TrainOptions::ending_weight).
constexpr int kEndingTargets = 2;

// Whether sample `s` of world `w` is of a mission's ending: its robot's own
// belief holds 1 to kEndingTargets targets above eps.
bool EndingSample(const DatasetSample& s, const DatasetWorld& w) {
  const double log_eps = std::log(w.eps);
  int open = 0;
  for (const HeatSource& t : s.targets) open += t.log_det > log_eps ? 1 : 0;
  return open >= 1 && open <= kEndingTargets;
}

// Renders samples idx[0, n) into `images`, labels and weights (a weak label
// weighs weak_weight, a sample whose acting policy's move differs from the
// label mistake_weight times as much, one of a mission's ending
// ending_weight times as much); with c->valid, `offsets` (n x 4) gets
// 0 for a valid move and -1e9 for another (the label's move always counts,
// should the nearest lattice point differ from the robot's), added to the
// logits so the loss is the choice among the valid moves.
void MakeBatch(Corpus* c, const int* idx, int n, double weak_weight,
               double mistake_weight, double ending_weight, int* height,
               int* width, std::vector<float>* images,
               std::vector<int64_t>* labels, std::vector<float>* weights,
               std::vector<char>* useful, std::vector<float>* offsets) {
  const ChannelRenderer& r0 = c->renderers[c->data.samples[idx[0]].world];
  *height = r0.height();
  *width = r0.width();
  const std::size_t size = r0.ImageSize();
  images->resize(size * n);
  labels->resize(n);
  weights->resize(n);
  useful->resize(n);
  for (int b = 0; b < n; ++b) {
    const DatasetSample& s = c->data.samples[idx[b]];
    ChannelRenderer& r = c->renderers[s.world];
    if (r.height() != *height || r.width() != *width)
      throw InputError::Flag(
          "--data",
          "worlds of different sizes in the global frame; use "
          "--frame centred or one workspace size");
    const DatasetWorld& w = c->data.worlds[s.world];
    r.Render(s.position, s.neighbours, s.targets, w.log_det_prior, w.eps,
             images->data() + b * size, SampleMemory(s, w));
    (*labels)[b] = static_cast<int64_t>(s.label);
    (*weights)[b] = static_cast<float>(
        (s.useful ? 1.0 : weak_weight) *
        (s.acted != s.label ? mistake_weight : 1.0) *
        (ending_weight != 1.0 && EndingSample(s, w) ? ending_weight : 1.0));
    (*useful)[b] = s.useful;
  }
  offsets->clear();
  if (c->valid.empty()) return;
  offsets->resize(static_cast<std::size_t>(n) * kNumMoves);
  for (int b = 0; b < n; ++b) {
    const std::uint8_t bits =
        c->valid[idx[b]] | (1u << static_cast<int>((*labels)[b]));
    for (int m = 0; m < kNumMoves; ++m)
      (*offsets)[static_cast<std::size_t>(b) * kNumMoves + m] =
          (bits >> m) & 1u ? 0.0f : -1e9f;
  }
}

// The logits the loss reads: among the valid moves when `offsets` is given
// (MakeBatch), else as they are.
torch::Tensor LossLogits(const torch::Tensor& logits,
                         std::vector<float>* offsets) {
  if (offsets->empty()) return logits;
  return logits +
         torch::from_blob(offsets->data(), {logits.size(0), kNumMoves});
}

ValidationResult Evaluate(IgbNetModule& module, Corpus* c, int hops) {
  ValidationResult r;  // NaN: no held-out samples
  if (c->val.empty()) return r;
  module->eval();
  torch::NoGradGuard no_grad;
  const int channels = c->renderers.front().channels();
  std::vector<float> images, weights, offsets;
  std::vector<int64_t> labels;
  std::vector<char> useful;
  long useful_n = 0, useful_right = 0, right = 0;
  double loss = 0.0;
  constexpr int kBatch = 128;
  std::vector<std::vector<int>> batches;
  if (hops > 0) {
    batches = StepBatches(*c, c->val, kBatch);
  } else {
    for (std::size_t first = 0; first < c->val.size(); first += kBatch)
      batches.emplace_back(
          c->val.begin() + first,
          c->val.begin() + std::min(c->val.size(), first + kBatch));
  }
  std::vector<int> rows;
  TeamGraph graph;
  for (const std::vector<int>& centres : batches) {
    const int n = static_cast<int>(centres.size());
    if (hops > 0) {
      GraphRows(*c, centres, hops, &rows, &graph);
    } else {
      rows = centres;
    }
    const int m = static_cast<int>(rows.size());
    int h = 0, w = 0;
    MakeBatch(c, rows.data(), m, 1.0, 1.0, 1.0, &h, &w, &images, &labels,
              &weights, &useful, &offsets);
    const torch::Tensor x =
        torch::from_blob(images.data(), {m, channels, h, w});
    const torch::Tensor y = torch::from_blob(labels.data(), {n}, torch::kInt64);
    const torch::Tensor logits = LossLogits(
        hops > 0 ? module->forward(x, ToTensors(graph)).narrow(0, 0, n)
                 : module->forward(x),
        &offsets);
    loss += torch::nn::functional::cross_entropy(
                logits, y,
                torch::nn::functional::CrossEntropyFuncOptions().reduction(
                    torch::kSum))
                .item<double>();
    const torch::Tensor pred = logits.argmax(1);
    const auto* p = pred.data_ptr<int64_t>();
    for (int b = 0; b < n; ++b) {
      const bool ok = p[b] == labels[b];
      right += ok;
      if (useful[b]) {
        ++useful_n;
        useful_right += ok;
      }
    }
  }
  r.samples = static_cast<long>(c->val.size());
  r.loss = loss / r.samples;
  r.acc = static_cast<double>(right) / r.samples;
  r.acc_useful = useful_n ? static_cast<double>(useful_right) / useful_n
                          : std::numeric_limits<double>::quiet_NaN();
  return r;
}

std::string OptionsKey(const TrainOptions& o) {
  std::ostringstream s;
  s.precision(17);
  s << o.network.ToJson() << " epochs=" << o.epochs << " batch=" << o.batch
    << " lr=" << o.lr << " lr_min=" << o.lr_min
    << " weight_decay=" << o.weight_decay << " weak_weight=" << o.weak_weight
    << " val_share=" << o.val_share << " seed=" << o.seed << " init=" << o.init;
  // Added after checkpoints were first written: only when set, so that the
  // checkpoints of earlier runs resume.
  if (o.valid_moves != 0) s << " valid_moves=" << o.valid_moves;
  if (o.mistake_weight != 1.0) s << " mistake_weight=" << o.mistake_weight;
  if (o.ending_weight != 1.0) s << " ending_weight=" << o.ending_weight;
  for (const std::string& d : o.data) s << " data=" << d;
  return s.str();
}

// What a dataset holds, in short: its sample and world counts and a hash of
// every world's episode, seed and steps and every sample's place and label.
std::string DataFingerprint(const Dataset& d) {
  std::string bytes;
  bytes.reserve(24 * d.worlds.size() + 32 * d.samples.size());
  const auto add = [&bytes](std::int64_t v) {
    bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
  };
  for (const DatasetWorld& w : d.worlds) {
    add(w.episode);
    add(w.seed);
    add(w.steps);
  }
  for (const DatasetSample& s : d.samples) {
    add(s.episode);
    add(s.step);
    add(s.robot);
    add(static_cast<std::int64_t>(s.label));
  }
  return std::to_string(d.samples.size()) + "/" +
         std::to_string(d.worlds.size()) + "/" + Sha256Hex(bytes).substr(0, 16);
}

torch::Tensor StringTensor(const std::string& text) {
  torch::Tensor t =
      torch::empty({static_cast<int64_t>(text.size())}, torch::kUInt8);
  std::memcpy(t.data_ptr(), text.data(), text.size());
  return t;
}

std::string TensorString(torch::Tensor t) {
  t = t.to(torch::kUInt8).contiguous();
  return std::string(reinterpret_cast<const char*>(t.data_ptr()), t.numel());
}

// The checkpoint's log: one ExactLine per epoch (NaN as "nan"). A log of an
// older build (space-separated too, reals with 17 digits) reads the same.
std::vector<EpochLog> ParseLog(const std::string& text) {
  std::vector<EpochLog> logs;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    EpochLog e;
    if (!ParseExactLine(line, &e)) break;
    logs.push_back(e);
  }
  return logs;
}

// Every flag against its declaration (TrainOptions and NetworkConfig), with
// the scenario keys' error form: `command line: --flag: what`.
void CheckOptions(const TrainOptions& o) {
  TrainOptions own = o;
  CheckFlags(&own);
  NetworkConfig network = o.network;
  CheckFlags(&network);
  if (o.out.empty())
    throw InputError::Flag("--out", "is required (the model file to write)");
}

// OUT and OUT.pt write the same log (TrainLogPath drops ".pt"): a run of one
// would replace the other's. Refused while the other's model or checkpoint
// file is there.
void CheckTheLogIsOurs(const std::string& out) {
  const bool pt = out.size() > 3 && out.compare(out.size() - 3, 3, ".pt") == 0;
  const std::string other = pt ? out.substr(0, out.size() - 3) : out + ".pt";
  std::error_code ec;
  // Files only: a folder of that name (the dataset `--data data/small`
  // beside `--out data/small.pt`) is no model.
  for (const std::string& f : {other, CheckpointPath(other)})
    if (std::filesystem::is_regular_file(f, ec))
      throw InputError::Flag("--out",
                             "'" + f + "' is there, and the model '" + other +
                                 "' writes the same log as this one ('" +
                                 TrainLogPath(out) +
                                 "'), which this run would replace: choose "
                                 "another name");
  // OUT is itself the checkpoint or the log of a model that is there.
  const auto ends = [&](const std::string& tail) {
    return out.size() > tail.size() &&
           out.compare(out.size() - tail.size(), tail.size(), tail) == 0;
  };
  std::vector<std::string> owners;
  if (ends(".ckpt")) owners.push_back(out.substr(0, out.size() - 5));
  if (ends(".train.csv")) {
    const std::string base = out.substr(0, out.size() - 10);
    owners.insert(owners.end(), {base, base + ".pt"});
  }
  for (const std::string& model : owners)
    if (std::filesystem::is_regular_file(model, ec))
      throw InputError::Flag("--out",
                             "'" + out + "' is what the model '" + model +
                                 "', which is there, keeps beside it (its " +
                                 (ends(".ckpt") ? "checkpoint" : "log") +
                                 "): choose another name");
}

// No file written (the model, its checkpoint, its log) may be a file read:
// a dataset file of --data, or the --init model. --init M --out M is
// refused too: the first epoch would replace the starting point, so a run
// started again (or one killed before its first checkpoint) would start
// from a half-trained model.
void CheckOutputsAreNotInputs(const TrainOptions& o) {
  std::vector<InputFile> inputs;
  for (const std::string& f : DatasetFiles(o.data, "--data"))
    inputs.push_back({f, "a dataset file of --data"});
  if (!o.init.empty())
    inputs.push_back({o.init, "the model to start from (--init)"});
  const std::pair<std::string, std::string> outputs[] = {
      {o.out, ""},
      {CheckpointPath(o.out), "the checkpoint written next to the model"},
      {TrainLogPath(o.out), "the log written next to the model"}};
  for (const auto& [path, written] : outputs) {
    CheckNotAnInput(path, "--out", inputs, written);
    // A FIFO, device or folder: found before any training, not when the
    // first epoch is saved.
    if (const std::string why = OutputFileProblem(path, written); !why.empty())
      throw InputError::Flag("--out", why);
    // A new *.sqlite file in a --data folder would be read as data next
    // time.
    const std::filesystem::path p(path);
    if (p.extension() != ".sqlite") continue;
    for (const std::string& d : o.data) {
      std::filesystem::path parent = p.parent_path();
      if (parent.empty()) parent = ".";
      std::error_code ec;
      if (std::filesystem::is_directory(d, ec) && SameFile(parent.string(), d))
        throw InputError::Flag(
            "--out", "'" + path + "'" +
                         (written.empty() ? "" : " (" + written + ")") +
                         " would be read as a dataset file of --data '" + d +
                         "'; choose another path");
    }
  }
}

}  // namespace

namespace {

// The network to train: --init's (its architecture and channels; extended,
// as the same function, where --reach-world, --search, --trail, --centre or
// --message-hops ask for more; its reach channel's contrast changed by
// --geodesic-length and --reach-detour), or a fresh one. o->network becomes its
// configuration.
std::unique_ptr<TorchNet> NetworkToTrain(TrainOptions* o) {
  // What the flags change in the network (--reach-world and --search
  // redefine channel 4, ChannelParams), checked.
  const auto redefine = [o](NetworkConfig* n) {
    ChannelParams* c = &n->channels;
    if (o->reach_world >= 0) c->reach_world = o->reach_world == 1;
    if (o->search >= 0) c->search = o->search == 1;
    if (o->trail >= 0) c->trail = o->trail == 1;
    if (o->centre >= 0) n->centre = o->centre;
    if (o->message_hops >= 0) n->message_hops = o->message_hops;
    if (o->geodesic_length > 0.0) c->geodesic_length = o->geodesic_length;
    if (o->reach_detour >= 0.0) c->reach_detour = o->reach_detour;
    if (o->reach_broad >= 0.0) c->reach_broad = o->reach_broad;
    if (o->reach_second >= 0) c->reach_second = o->reach_second == 1;
    if (o->neighbour_cap >= 0) c->neighbour_cap = o->neighbour_cap;
    if (const auto [key, needs] = c->MissingPrerequisite(); !key.empty()) {
      std::string flag = "--" + std::string(key);
      std::replace(flag.begin(), flag.end(), '_', '-');
      throw InputError::Flag(flag,
                             needs == "geodesic"
                                 ? "needs the reach channel (--geodesic, or an "
                                   "--init model with it)"
                                 : "needs --reach-world 1");
    }
    if (o->geodesic_length > 0.0 && !c->geodesic)
      throw InputError::Flag(
          "--geodesic-length",
          "needs the reach channel (--geodesic, or an --init "
          "model with it)");
    if (const std::string problem = n->CentreProblem(); !problem.empty())
      throw InputError::Flag("--centre", problem);
  };
  if (o->init.empty()) {
    redefine(&o->network);
    return std::make_unique<TorchNet>(o->network, o->seed);
  }
  std::unique_ptr<TorchNet> net =
      TorchNet::Load(o->init, "command line", 0, "--init");
  const NetworkConfig before = net->config();
  o->network = before;
  redefine(&o->network);
  if (o->network.message_hops < before.message_hops)
    throw InputError::Flag("--message-hops",
                           "the --init model passes messages over " +
                               std::to_string(before.message_hops) +
                               " hops; it can be extended, not cut");
  if (before.centre > 0 && o->network.centre != before.centre)
    throw InputError::Flag(
        "--centre", "the --init model reads a centre of " +
                        std::to_string(before.centre) +
                        " cells; it can be added to a model without one, "
                        "not changed");
  if (o->network.ToJson() == before.ToJson()) return net;
  // The stem's weights are kept by input channel index, so the channels
  // both models have must keep their places: one added after the last, or
  // the last ones removed, not one put in between.
  const std::vector<std::string> had = before.channels.names(),
                                 has = o->network.channels.names();
  if (!std::equal(had.begin(), had.begin() + std::min(had.size(), has.size()),
                  has.begin()))
    throw InputError::Flag(
        "--init", "the model's input channels (" + field_text::Join(had) +
                      ") would not keep their places among those asked "
                      "for (" +
                      field_text::Join(has) +
                      "): a channel can be added after the last, or the "
                      "last ones removed");
  // The same weights: a new channel 4 is read by the same stem, and what
  // is added (a trail channel, the centre, message hops) starts at zero
  // weight; a trail channel removed is dropped.
  auto extended = std::make_unique<TorchNet>(o->network, o->seed);
  Transplant(net->impl().module, extended->impl().module);
  return extended;
}

// One training run at a time in OUT's folder (an flock on the folder,
// released when the run ends or dies); then the temporary files that killed
// runs left there are removed.
std::unique_ptr<FileLock> LockOutputFolder(const std::string& out) {
  std::filesystem::path parent = std::filesystem::path(out).parent_path();
  if (parent.empty()) parent = ".";
  std::unique_ptr<FileLock> lock;
  try {
    CheckReplaceableFile(out);  // before its folder is made: `--out DIR/`
    MakeDirs(parent.string());
    lock = std::make_unique<FileLock>(parent.string());
  } catch (const std::runtime_error& e) {
    throw InputError::Flag("--out", e.what());
  }
  // A folder no file can be made in (/proc, read-only): refused before the
  // first epoch, not when the model is written.
  if (const std::string why = UnwritableDirProblem(parent.string());
      !why.empty())
    throw InputError::Flag("--out", why);
  // OUT, OUT.ckpt and the log share OUT's name without ".pt".
  std::string prefix = std::filesystem::path(out).filename().string();
  if (prefix.size() > 3 && prefix.compare(prefix.size() - 3, 3, ".pt") == 0)
    prefix.resize(prefix.size() - 3);
  RemoveStaleTemporaries(parent.string(), prefix);
  return lock;
}

// --resume: the model, optimizer state and log of the checkpoint, which must
// have been written with the same options (`key`). Returns the epochs done.
int ResumeFromCheckpoint(const std::string& ckpt, const std::string& key,
                         const std::string& legacy_key, IgbNetModule& module,
                         torch::optim::Adam* optimizer,
                         std::vector<EpochLog>* logs) {
  try {
    // Read by aia's reader (never blocks; a bounded size) and checked as a
    // model file is (its container, and every tensor's size against its
    // entry) before libtorch reads it.
    const std::string bytes = ReadFile(ckpt, std::uintmax_t{1} << 31);
    if (const std::string damage = ArchiveDamage(bytes); !damage.empty())
      throw std::runtime_error(damage);
    torch::serialize::InputArchive archive, model_archive, optim_archive;
    archive.load_from(bytes.data(), bytes.size());
    torch::Tensor t;
    archive.read("options", t, true);
    // A checkpoint of an earlier build holds the key without the threads
    // and the data's fingerprint.
    const std::string written = TensorString(t);
    if (written != key && written != legacy_key) {
      // The same options and threads, other data (the fingerprint is last).
      const std::string options = key.substr(0, key.rfind(" data=") + 6);
      const bool data = written.rfind(options, 0) == 0;
      throw InputError(
          ckpt, 0, "--resume",
          data ? "was written on other data (the dataset grew, shrank or "
                 "changed since: its samples would count in some epochs "
                 "and not others); run without --resume"
               : "was written with other options (the thread count "
                 "included, --threads or else libtorch's default, "
                 "OMP_NUM_THREADS where set: the weights depend on it); run "
                 "without --resume or with the same options");
    }
    archive.read("epoch", t, true);
    const int done = static_cast<int>(t.item<int64_t>());
    archive.read("model", model_archive);
    archive.read("optimizer", optim_archive);
    module->load(model_archive);
    optimizer->load(optim_archive);
    archive.read("log", t, true);
    *logs = ParseLog(TensorString(t));
    return done;
  } catch (const InputError&) {
    throw;
  } catch (const c10::Error& e) {
    // libtorch's message without its C++ backtrace (one line, as every
    // error): a model file or another archive where the checkpoint was.
    throw InputError(ckpt, 0, "--resume",
                     std::string("cannot read the checkpoint: ") +
                         e.what_without_backtrace());
  } catch (const std::bad_alloc&) {
    throw;  // out of memory is not bad input (cli.cc says it)
  } catch (const std::exception& e) {
    throw InputError(ckpt, 0, "--resume",
                     std::string("cannot read the checkpoint: ") + e.what());
  }
}

// Cosine from lr to lr_min over every batch of every epoch.
struct LrSchedule {
  double lr, lr_min;
  long total_steps;
  // `step` counts batches of --batch samples (fractional with message
  // passing, whose batches are whole steps).
  double At(double step) const {
    return lr_min +
           0.5 * (lr - lr_min) *
               (1.0 + std::cos(M_PI * step / static_cast<double>(total_steps)));
  }
};

// An epoch's batches of training samples, shuffled by the epoch's stream.
// With message passing, whole steps are shuffled, so that a robot's
// neighbours are in its batch.
std::vector<std::vector<int>> EpochBatches(const Corpus& corpus,
                                           const TrainOptions& o, int epoch,
                                           long steps_per_epoch, int hops) {
  std::vector<int> order = corpus.train;
  Rng rng(o.seed, "train/shuffle", static_cast<std::uint64_t>(epoch));
  std::vector<std::vector<int>> batches;
  if (hops > 0) {
    std::vector<std::pair<int, int>> steps;  // ranges of `order`
    for (std::size_t i = 0; i < order.size();) {
      std::size_t e = i + 1;
      while (e < order.size() && SameStep(corpus, order[e], order[i])) ++e;
      steps.emplace_back(static_cast<int>(i), static_cast<int>(e));
      i = e;
    }
    for (std::size_t i = steps.size(); i > 1; --i)
      std::swap(steps[i - 1], steps[rng.UniformInt(i)]);
    std::vector<int> shuffled;
    shuffled.reserve(order.size());
    for (const auto& [b, e] : steps)
      shuffled.insert(shuffled.end(), order.begin() + b, order.begin() + e);
    return StepBatches(corpus, shuffled, o.batch);
  }
  for (std::size_t i = order.size(); i > 1; --i)
    std::swap(order[i - 1], order[rng.UniformInt(i)]);
  for (long s = 0; s < steps_per_epoch; ++s) {
    const std::size_t first = static_cast<std::size_t>(s) * o.batch;
    batches.emplace_back(
        order.begin() + first,
        order.begin() + std::min(order.size(), first + o.batch));
  }
  return batches;
}

// Scratch memory of the batches, kept across epochs.
struct BatchScratch {
  std::vector<float> images, weights, offsets;
  std::vector<int64_t> labels;
  std::vector<char> useful;
  std::vector<int> rows;
  TeamGraph graph;
};

// One epoch of Adam steps over `batches`: the log's training columns (lr,
// loss, accuracy, samples).
EpochLog TrainEpoch(IgbNetModule& module, torch::optim::Adam* optimizer,
                    Corpus* corpus,
                    const std::vector<std::vector<int>>& batches,
                    const TrainOptions& o, const LrSchedule& schedule,
                    int epoch, long steps_per_epoch, int hops, BatchScratch* b,
                    ProgressLine* progress) {
  const auto t0 = Clock::now();
  module->train();
  double loss_sum = 0.0, weight_sum = 0.0;
  long right = 0, seen = 0, consumed = 0;
  double lr = o.lr;
  const int channels = corpus->renderers.front().channels();
  const long num_batches = static_cast<long>(batches.size());
  for (long s = 0; s < num_batches; ++s) {
    const std::vector<int>& centres = batches[s];
    const int n = static_cast<int>(centres.size());
    if (hops > 0) {
      GraphRows(*corpus, centres, hops, &b->rows, &b->graph);
    } else {
      b->rows = centres;
    }
    const int m = static_cast<int>(b->rows.size());
    if (m < 2) break;  // batch norm needs two samples
    int h = 0, w = 0;
    MakeBatch(corpus, b->rows.data(), m, o.weak_weight, o.mistake_weight,
              o.ending_weight, &h, &w, &b->images, &b->labels, &b->weights,
              &b->useful, &b->offsets);
    lr = schedule.At(static_cast<double>(epoch * steps_per_epoch) +
                     (hops > 0 ? static_cast<double>(consumed) / o.batch
                               : static_cast<double>(s)));
    consumed += n;
    for (auto& group : optimizer->param_groups())
      static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
    const torch::Tensor x =
        torch::from_blob(b->images.data(), {m, channels, h, w});
    const torch::Tensor y =
        torch::from_blob(b->labels.data(), {n}, torch::kInt64);
    const torch::Tensor wt = torch::from_blob(b->weights.data(), {n});
    const torch::Tensor logits = LossLogits(
        hops > 0 ? module->forward(x, ToTensors(b->graph)).narrow(0, 0, n)
                 : module->forward(x),
        &b->offsets);
    const torch::Tensor per = torch::nn::functional::cross_entropy(
        logits, y,
        torch::nn::functional::CrossEntropyFuncOptions().reduction(
            torch::kNone));
    const double wsum = wt.sum().item<double>();
    if (wsum <= 0.0) continue;
    const torch::Tensor loss = (per * wt).sum() / wsum;
    const double value = loss.item<double>();
    // A step on it would make every weight NaN, saved into the model and
    // the checkpoint (which the loader then refuses): stop before that.
    if (!std::isfinite(value))
      throw std::runtime_error(
          "epoch " + std::to_string(epoch + 1) + ", batch " +
          std::to_string(s + 1) +
          ": the training loss is not finite; nothing of this epoch is "
          "saved (a lower --lr, or data without extreme values)");
    optimizer->zero_grad();
    loss.backward();
    optimizer->step();
    loss_sum += value * wsum;
    weight_sum += wsum;
    const torch::Tensor pred = logits.argmax(1);
    right += (pred == y).sum().item<int64_t>();
    seen += n;
    if (s % 50 == 0 || s + 1 == num_batches) {
      char line[160];
      std::snprintf(line, sizeof line,
                    "[train] epoch %d/%d  batch %ld/%ld  loss %.4f  acc %.3f  "
                    "%.0f samples/s",
                    epoch + 1, o.epochs, s + 1, num_batches,
                    loss_sum / std::max(weight_sum, 1e-12),
                    static_cast<double>(right) / std::max(seen, 1L),
                    seen / std::max(SecondsSince(t0), 1e-9));
      progress->Update(line);
    }
  }
  EpochLog e;
  e.epoch = epoch + 1;
  e.lr = lr;
  e.train_loss = loss_sum / std::max(weight_sum, 1e-12);
  e.train_acc = static_cast<double>(right) / std::max(seen, 1L);
  e.samples = seen;
  return e;
}

// The log beside the model (TrainLogPath), the epochs so far.
void WriteTrainLog(const std::string& out, const std::vector<EpochLog>& logs) {
  std::string csv = CsvHeader<EpochLog>() + "\n";
  for (const EpochLog& l : logs) csv += CsvLine(l);
  WriteFileAtomic(TrainLogPath(out), csv);
}

// After an epoch: the model (OUT), the checkpoint (model, optimizer, epochs
// done, options, log) and the log (CSV), each written atomically.
void SaveEpoch(const TrainOptions& o, const TorchNet& net, IgbNetModule& module,
               torch::optim::Adam& optimizer, const std::string& key,
               const std::vector<EpochLog>& logs) {
  std::filesystem::path parent = std::filesystem::path(o.out).parent_path();
  if (!parent.empty()) MakeDirs(parent.string());
  net.Save(o.out);
  {
    torch::serialize::OutputArchive archive, model_archive, optim_archive;
    module->save(model_archive);
    optimizer.save(optim_archive);
    archive.write("model", model_archive);
    archive.write("optimizer", optim_archive);
    archive.write("epoch",
                  torch::tensor(static_cast<int64_t>(logs.back().epoch)), true);
    archive.write("options", StringTensor(key), true);
    std::ostringstream log;
    log.precision(17);
    for (const EpochLog& l : logs)
      log << l.epoch << ' ' << l.lr << ' ' << l.train_loss << ' ' << l.train_acc
          << ' ' << l.val_loss << ' ' << l.val_acc << ' ' << l.val_acc_useful
          << ' ' << l.samples << ' ' << l.seconds << '\n';
    archive.write("log", StringTensor(log.str()), true);
    SaveArchiveAtomic(archive, CheckpointPath(o.out));
  }
  WriteTrainLog(o.out, logs);
}

// build/aia keeps every page it frees (tools/aia_main.cc: no decay), which
// doubles inference speed. Training a network with a centre or message
// passing then grows without bound (on the learned recipe's data about
// 100 MB a second, 18 GB after three minutes; without either the process
// stays at 2.7 GB; the cause inside libtorch is not known): for those,
// pages freed for a second are returned (2.6 GB; training 10 to 20 %
// slower).
void ReturnFreedPagesWhileTraining(const NetworkConfig& network) {
  if (!mallctl || (network.centre == 0 && network.message_hops == 0)) return;
  ssize_t ms = 1000;
  unsigned arenas = 0;
  std::size_t size = sizeof arenas;
  if (mallctl("arenas.narenas", &arenas, &size, nullptr, 0) != 0) return;
  for (const char* decay : {"dirty_decay_ms", "muzzy_decay_ms"}) {
    // The arenas made from now on, and those there already (one not in use
    // refuses; there is nothing to set in it).
    mallctl((std::string("arenas.") + decay).c_str(), nullptr, nullptr, &ms,
            sizeof ms);
    for (unsigned i = 0; i < arenas; ++i)
      mallctl(("arena." + std::to_string(i) + "." + decay).c_str(), nullptr,
              nullptr, &ms, sizeof ms);
  }
}

}  // namespace

std::vector<EpochLog> TorchTrain(const TrainOptions& options) {
  TrainOptions o = options;
  CheckOptions(o);
  if (o.threads > 0) torch::set_num_threads(o.threads);
  const std::unique_ptr<TorchNet> net = NetworkToTrain(&o);
  const int hops = o.network.message_hops;
  CheckOutputsAreNotInputs(o);
  CheckTheLogIsOurs(o.out);
  ReturnFreedPagesWhileTraining(o.network);
  IgbNetModule& module = net->impl().module;
  torch::optim::Adam optimizer(
      module->parameters(),
      torch::optim::AdamOptions(o.lr).weight_decay(o.weight_decay));
  const std::unique_ptr<FileLock> lock = LockOutputFolder(o.out);
  if (o.epochs == 0) {  // --init's weights as NetworkToTrain made them
    // A checkpoint of OUT would describe another model, and a --resume
    // from it would keep this one: refused, as --resume is.
    std::error_code ec;
    if (o.resume)
      throw InputError::Flag("--resume",
                             "--epochs 0 trains nothing: there is nothing to "
                             "resume; drop the flag");
    if (std::filesystem::exists(CheckpointPath(o.out), ec))
      throw InputError::Flag(
          "--out", "'" + CheckpointPath(o.out) +
                       "' is there (a training run of this model); "
                       "--epochs 0 would write a model it does not "
                       "describe beside it: remove it or choose another "
                       "--out");
    net->Save(o.out);
    return {};
  }
  Corpus corpus = LoadCorpus(o.data, o.network.channels, o.val_share, o.seed,
                             o.weak_weight, o.valid_moves != 0);
  // The weights depend on the thread count and on every sample: a resume
  // with other threads or on a dataset that changed since is refused.
  const std::string legacy_key = OptionsKey(o);
  // The threads libtorch trains on: --threads, else its own default
  // (OMP_NUM_THREADS where set, else from the machine's cores: one on a
  // 2-core machine, two on a 4-core one), recorded as used.
  const int threads = torch::get_num_threads();
  const std::string key = legacy_key + " threads=" + std::to_string(threads) +
                          " data=" + DataFingerprint(corpus.data);
  const std::string ckpt = CheckpointPath(o.out);
  int start = 0;
  std::vector<EpochLog> logs;
  std::error_code ec;
  if (o.resume && std::filesystem::exists(ckpt, ec))
    start =
        ResumeFromCheckpoint(ckpt, key, legacy_key, module, &optimizer, &logs);
  if (start >= o.epochs) {
    // Done: the log as the checkpoint has it (a run killed after its last
    // checkpoint and before its log was one epoch short).
    WriteTrainLog(o.out, logs);
    return logs;
  }

  if (corpus.train.empty())
    throw InputError::Flag("--data",
                           "leaves no training samples after the split");
  if (hops > 0) LinkNeighbours(&corpus);
  if (o.progress)
    std::fprintf(stderr,
                 "[train] %zu worlds, %zu samples: %zu for training, %zu held "
                 "out (%zu worlds); %lld parameters\n",
                 corpus.data.worlds.size(), corpus.data.samples.size(),
                 corpus.train.size(), corpus.val.size(),
                 static_cast<std::size_t>(std::count(
                     corpus.val_world.begin(), corpus.val_world.end(), 1)),
                 static_cast<long long>(net->NumParameters()));

  const long steps_per_epoch =
      (static_cast<long>(corpus.train.size()) + o.batch - 1) / o.batch;
  const LrSchedule schedule{o.lr, o.lr_min, steps_per_epoch * o.epochs};
  BatchScratch scratch;
  ProgressLine progress(o.progress);
  for (int epoch = start; epoch < o.epochs; ++epoch) {
    if (o.stop_after_epochs > 0 && epoch - start >= o.stop_after_epochs) break;
    const auto t0 = Clock::now();
    const std::vector<std::vector<int>> batches =
        EpochBatches(corpus, o, epoch, steps_per_epoch, hops);
    EpochLog e = TrainEpoch(module, &optimizer, &corpus, batches, o, schedule,
                            epoch, steps_per_epoch, hops, &scratch, &progress);
    const ValidationResult v = Evaluate(module, &corpus, hops);
    e.val_loss = v.loss;
    e.val_acc = v.acc;
    e.val_acc_useful = v.acc_useful;
    e.seconds = SecondsSince(t0);
    logs.push_back(e);
    module->eval();
    SaveEpoch(o, *net, module, optimizer, key, logs);
    if (o.progress) {
      char line[400];
      std::snprintf(line, sizeof line,
                    "[train] epoch %d/%d: loss %.4f acc %.3f | %s | %.0f s, "
                    "%.0f samples/s",
                    e.epoch, o.epochs, e.train_loss, e.train_acc,
                    ValidationText(e).c_str(), e.seconds,
                    e.samples / std::max(e.seconds, 1e-9));
      progress.Print(line);
    }
  }
  return logs;
}

ValidationResult TorchValidate(const std::string& model,
                               const std::vector<std::string>& data,
                               double val_share, std::uint64_t seed,
                               bool valid_moves) {
  std::unique_ptr<TorchNet> net =
      TorchNet::Load(model, "command line", 0, "--validate");
  Corpus corpus = LoadCorpus(data, net->config().channels, val_share, seed, 1.0,
                             valid_moves);
  if (corpus.val.empty())
    throw InputError::Flag(
        "--val-share",
        "holds out none of the " + std::to_string(corpus.data.worlds.size()) +
            " worlds of --data: nothing to validate on (a larger "
            "--val-share, or more worlds)");
  const int hops = net->config().message_hops;
  if (hops > 0) LinkNeighbours(&corpus);
  return Evaluate(net->impl().module, &corpus, hops);
}

double TorchNetworkSpeed(const NetworkConfig& config, int height, int width,
                         int batch, bool train, int iterations, int repeats,
                         bool bf16) {
  TorchNet net(config, 1);
  IgbNetModule& module = net.impl().module;
  const torch::Tensor x =
      torch::rand({batch, config.channels.num_channels(), height, width});
  const torch::Tensor y = torch::randint(0, kNumMoves, {batch}, torch::kInt64);
  torch::optim::Adam optimizer(module->parameters(),
                               torch::optim::AdamOptions(1e-4));
  std::vector<float> images(x.numel()), logits(batch * kNumMoves);
  std::memcpy(images.data(), x.data_ptr<float>(), images.size() * 4);
  const auto once = [&] {
    if (train) {
      module->train();
      const torch::Tensor loss =
          torch::nn::functional::cross_entropy(module->forward(x), y);
      optimizer.zero_grad();
      loss.backward();
      optimizer.step();
    } else {
      net.Infer(images.data(), batch, height, width, false, bf16,
                logits.data());
    }
  };
  for (int i = 0; i < 3; ++i) once();
  std::vector<double> rates;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    for (int i = 0; i < iterations; ++i) once();
    rates.push_back(batch * iterations / SecondsSince(t0));
  }
  std::sort(rates.begin(), rates.end());
  return rates[rates.size() / 2];
}

}  // namespace aia
