// The learning pipeline end to end on tiny data: a dataset killed
// mid-episode and resumed reads back identical to one written in one go
// (an exception in flight and a real SIGKILL); a few training steps lower
// the loss; a training run stopped and resumed ends with the same model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>

#include "aia/commands/dataset_command.h"
#include "aia/core/hash.h"
#include "aia/core/io.h"
#include "aia/learning/dataset.h"
#include "aia/learning/network.h"
#include "aia/learning/trainer.h"
#include "support/test_support.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

DatasetOptions Tiny(const std::string& out) {
  DatasetOptions o;
  o.out = out;
  o.episodes = 4;
  o.size = {3, 3};
  o.keep = 3;
  o.first_seed = 500;
  o.progress = false;
  return o;
}

void ExpectSameDataset(const Dataset& a, const Dataset& b) {
  ASSERT_EQ(a.worlds.size(), b.worlds.size());
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.worlds.size(); ++i) {
    const DatasetWorld &x = a.worlds[i], &y = b.worlds[i];
    EXPECT_EQ(x.episode, y.episode);
    EXPECT_EQ(x.seed, y.seed);
    EXPECT_EQ(x.steps, y.steps);
    EXPECT_EQ(x.flowtime, y.flowtime);
    EXPECT_EQ(x.log_det_prior, y.log_det_prior);
    ASSERT_EQ(x.obstacles.size(), y.obstacles.size());
    for (std::size_t k = 0; k < x.obstacles.size(); ++k) {
      EXPECT_EQ(x.obstacles[k].lo, y.obstacles[k].lo);
      EXPECT_EQ(x.obstacles[k].hi, y.obstacles[k].hi);
    }
  }
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    const DatasetSample &x = a.samples[i], &y = b.samples[i];
    EXPECT_EQ(x.episode, y.episode);
    EXPECT_EQ(x.step, y.step);
    EXPECT_EQ(x.robot, y.robot);
    EXPECT_EQ(x.position, y.position);
    EXPECT_EQ(x.neighbours, y.neighbours);
    EXPECT_EQ(x.label, y.label);
    EXPECT_EQ(x.useful, y.useful);
    EXPECT_EQ(x.search, y.search);
    ASSERT_EQ(x.targets.size(), y.targets.size());
    for (std::size_t k = 0; k < x.targets.size(); ++k) {
      EXPECT_EQ(x.targets[k].mean, y.targets[k].mean);
      EXPECT_EQ(x.targets[k].cov, y.targets[k].cov);
      EXPECT_EQ(x.targets[k].log_det, y.targets[k].log_det);
    }
  }
}

TEST(DatasetTest, KilledMidEpisodeAndResumedReadsBackIdentical) {
  const std::string dir = testing::MakeTempDir("aia_ds_");
  EXPECT_EQ(RunDataset(Tiny(dir + "/whole")), 4);
  const Dataset whole = ReadDataset({dir + "/whole"}, "--data");
  EXPECT_EQ(whole.worlds.size(), 4u);
  EXPECT_GT(whole.samples.size(), 4u * 3u);

  DatasetOptions broken = Tiny(dir + "/resumed");
  broken.stop_after_episodes = 2;  // dies in the third episode
  EXPECT_EQ(RunDataset(broken), 2);
  EXPECT_EQ(ReadDataset({dir + "/resumed"}, "--data").worlds.size(), 2u);
  EXPECT_EQ(RunDataset(Tiny(dir + "/resumed")), 2);  // only what is missing
  ExpectSameDataset(whole, ReadDataset({dir + "/resumed"}, "--data"));
  EXPECT_EQ(RunDataset(Tiny(dir + "/resumed")), 0);  // nothing left

  // Two shards hold the same episodes between them.
  for (int k = 0; k < 2; ++k) {
    DatasetOptions s = Tiny(dir + "/sharded");
    s.shard = {k, 2};
    RunDataset(s);
  }
  const Dataset sharded = ReadDataset({dir + "/sharded"}, "--data");
  EXPECT_EQ(sharded.worlds.size(), 4u);
  EXPECT_EQ(sharded.samples.size(), whole.samples.size());
  fs::remove_all(dir);
}

// A dataset acted by a learned policy keeps its model's content in its
// recipe, not its path: a resume whose model file has other content
// (retrained, or the default resolved in another working folder) is
// refused, not mixed in; the same content by another path goes on.
TEST(DatasetTest, AResumeWithAnotherModelIsRefused) {
  const std::string dir = testing::MakeTempDir("aia_ds_model_");
  const std::string model = dir + "/m.pt";
  fs::copy_file(testing::SourcePath("models/igbnet_10x10.pt"), model);
  const std::vector<std::string> args = {
      "dataset", "--policy", "igbnet",      "--model", model,       "--size",
      "3x3",     "--out",    dir + "/data", "--quiet", "--episodes"};
  std::vector<std::string> first = args, second = args;
  first.push_back("2");
  second.push_back("3");
  ASSERT_EQ(testing::RunAia(first).exit_code, 0);
  fs::copy_file(testing::SourcePath("models/igbnet.pt"), model,
                fs::copy_options::overwrite_existing);
  const auto r = testing::RunAia(second);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("was written with another recipe"), std::string::npos)
      << r.err;
  fs::copy_file(testing::SourcePath("models/igbnet_10x10.pt"), model,
                fs::copy_options::overwrite_existing);
  EXPECT_EQ(testing::RunAia(second).exit_code, 0);  // the same model goes on
  // The same content by another path (a copy) is the same model: it goes
  // on (the recipe held the path as typed, and refused it).
  const std::string copy = dir + "/copy.pt";
  fs::copy_file(model, copy);
  std::vector<std::string> third = second;
  third[4] = copy;
  third.back() = "4";
  const auto c = testing::RunAia(third);
  EXPECT_EQ(c.exit_code, 0) << c.err;
  fs::remove_all(dir);
}

// OUT and OUT.pt share their log (the ".pt" is dropped): the second run
// replaced the first's log. It is refused while the other model is there,
// not for a folder of that name.
TEST(TrainTest, TwoModelsThatShareALogAreRefused) {
  const std::string dir = testing::MakeTempDir("aia_train_log_");
  ASSERT_EQ(testing::RunAia({"dataset", "--out", dir + "/data", "--episodes",
                             "2", "--size", "3x3", "--quiet"})
                .exit_code,
            0);
  const std::vector<std::string> train = {
      "train", "--data", dir + "/data", "--epochs", "1", "--quiet", "--out"};
  std::vector<std::string> pt = train, bare = train;
  pt.push_back(dir + "/m.pt");
  bare.push_back(dir + "/m");
  ASSERT_EQ(testing::RunAia(pt).exit_code, 0);
  const std::string log = testing::ReadFile(dir + "/m.train.csv");
  const auto r = testing::RunAia(bare);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(
      r.err.find("writes the same log as this one ('" + dir + "/m.train.csv')"),
      std::string::npos)
      << r.err;
  EXPECT_EQ(testing::ReadFile(dir + "/m.train.csv"), log);
  // Nor is a model written over the checkpoint or the log another keeps.
  const std::string checkpoint = testing::ReadFile(dir + "/m.pt.ckpt");
  for (const std::string& name : {"/m.pt.ckpt", "/m.train.csv"}) {
    std::vector<std::string> over = train;
    over.push_back(dir + name);
    const auto o = testing::RunAia(over);
    EXPECT_EQ(o.exit_code, 2) << name;
    EXPECT_NE(o.err.find("is what the model '" + dir + "/m"), std::string::npos)
        << o.err;
  }
  EXPECT_EQ(testing::ReadFile(dir + "/m.pt.ckpt"), checkpoint);
  EXPECT_EQ(testing::ReadFile(dir + "/m.train.csv"), log);
  // A folder is no model: the dataset DIR/data beside the model
  // DIR/data.pt (docs/paths.md's `--data data/small --out data/small.pt`).
  std::vector<std::string> beside = train;
  beside.push_back(dir + "/data.pt");
  const auto b = testing::RunAia(beside);
  EXPECT_EQ(b.exit_code, 0) << b.err;
  fs::remove_all(dir);
}

// --threads 0 trains on libtorch's default (OMP_NUM_THREADS where set): the
// checkpoint records the threads it really had, so that a resume on others
// (whose weights would match neither run) is refused. It recorded the cores.
TEST(TrainTest, AResumeOnOtherDefaultThreadsIsRefused) {
  const std::string dir = testing::MakeTempDir("aia_train_threads_");
  ASSERT_EQ(testing::RunAia({"dataset", "--out", dir + "/data", "--episodes",
                             "2", "--size", "3x3", "--quiet"})
                .exit_code,
            0);
  const auto train = [&](int omp, int epochs, bool resume) {
    return testing::RunCommand("OMP_NUM_THREADS=" + std::to_string(omp) + " " +
                               std::string(AIA_BINARY) + " train --data " +
                               dir + "/data --quiet --out " + dir +
                               "/m.pt --epochs " + std::to_string(epochs) +
                               (resume ? " --resume" : ""));
  };
  ASSERT_EQ(train(1, 1, false).exit_code, 0);
  const auto other = train(2, 1, true);
  EXPECT_EQ(other.exit_code, 2) << other.err;
  EXPECT_NE(other.err.find("thread count"), std::string::npos) << other.err;
  const auto same = train(1, 1, true);
  EXPECT_EQ(same.exit_code, 0) << same.err;
  fs::remove_all(dir);
}

TEST(DatasetTest, SigkilledCommandResumesToTheSameData) {
  const std::string dir = testing::MakeTempDir("aia_ds_");
  const std::vector<std::string> args = {
      "dataset", "--episodes", "12",           "--size", "4x4",
      "--keep",  "2",          "--first-seed", "900",    "--quiet"};
  std::vector<std::string> whole = args, killed = args;
  whole.insert(whole.end(), {"--out", dir + "/whole"});
  killed.insert(killed.end(), {"--out", dir + "/killed"});
  ASSERT_EQ(testing::RunAia(whole).exit_code, 0);
  // Killed at two moments (whatever is in flight then), then resumed.
  std::string line = "timeout -s KILL 0.4 " + std::string(AIA_BINARY);
  for (const std::string& a : killed) line += " '" + a + "'";
  testing::RunCommand(line);
  testing::RunCommand(line);
  const auto r = testing::RunAia(killed);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectSameDataset(ReadDataset({dir + "/whole"}, "--data"),
                    ReadDataset({dir + "/killed"}, "--data"));
  for (const auto& e : fs::directory_iterator(dir + "/killed"))
    EXPECT_EQ(e.path().extension(), ".sqlite") << e.path();  // no leftovers
  fs::remove_all(dir);
}

// An episode past --max-seconds is stopped, recorded as done without
// samples and counted; running the command again skips it.
TEST(DatasetTest, EpisodesPastMaxSecondsAreSkippedAndCounted) {
  const std::string dir = testing::MakeTempDir("aia_ds_");
  const std::vector<std::string> args = {
      "dataset", "--episodes",   "3",   "--size",  "3x3",           "--keep",
      "2",       "--first-seed", "700", "--quiet", "--max-seconds", "1e-9",
      "--out",   dir + "/d"};
  const auto r = testing::RunAia(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("3 episodes written now (3 of 3 done), 3 skipped "
                       "(over --max-seconds 1e-09)"),
            std::string::npos)
      << r.out;
  const Dataset d = ReadDataset({dir + "/d"}, "--data");
  EXPECT_EQ(d.worlds.size(), 3u);
  EXPECT_TRUE(d.samples.empty());
  for (const DatasetWorld& w : d.worlds) EXPECT_EQ(w.flowtime, -1);
  const auto again = testing::RunAia(args);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("0 episodes written now (3 of 3 done), 0 skipped"),
            std::string::npos)
      << again.out;
  const auto bad =
      testing::RunAia({"dataset", "--max-seconds", "-1", "--out", dir + "/e"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.err,
            "error: command line: --max-seconds: must be a number in [0, "
            "10000000], got -1\n");
  fs::remove_all(dir);
}

TEST(DatasetTest, ResumingWithAnotherRecipeIsRefused) {
  const std::string dir = testing::MakeTempDir("aia_ds_");
  DatasetOptions o = Tiny(dir);
  o.episodes = 1;
  RunDataset(o);
  o.keep = 5;
  try {
    RunDataset(o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(e.Format().find("another recipe"), std::string::npos);
  }
  EXPECT_THROW(ReadDataset({dir + "/none"}, "--data"), InputError);
  fs::remove_all(dir);
}

// Shards written at once into one folder (an mpirun's ranks, or --shard
// K/N jobs started together): each checks the others' recipes, and another
// writer's shard may not have its tables yet. An empty shard holds no
// recipe; one that another process holds is read again until it has one
// (the two-rank test failed once in CI: "no such table: meta").
TEST(DatasetTest, AShardAnotherWriterIsStillMakingIsWaitedFor) {
  const std::string dir = testing::MakeTempDir("aia_ds_");
  const std::vector<std::string> flags = {
      "dataset", "--episodes", "2", "--size", "3x2", "--keep", "2", "--quiet"};
  const auto shard = [&](const std::string& k, const std::string& out) {
    std::vector<std::string> a = flags;
    for (const std::string& f :
         {std::string("--shard"), k + "/2", std::string("--out"), out})
      a.push_back(f);
    return a;
  };
  ASSERT_EQ(testing::RunAia(shard("1", dir + "/ref")).exit_code, 0);
  const std::string ref = dir + "/ref/shard-1-of-2.sqlite";
  // An empty file (a writer that has just created it).
  fs::create_directories(dir + "/a");
  std::FILE* f = std::fopen((dir + "/a/shard-1-of-2.sqlite").c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  const auto empty = testing::RunAia(shard("0", dir + "/a"));
  EXPECT_EQ(empty.exit_code, 0) << empty.err;
  // Another process holds the shard, its database without tables of ours
  // for a second, then the shard's bytes.
  fs::create_directories(dir + "/b");
  const std::string writer =
      "import fcntl, os, sqlite3, sys, time\n"
      "path, ref, marker = sys.argv[1:4]\n"
      "f = open(path, 'a+b')\n"
      "fcntl.flock(f, fcntl.LOCK_EX)\n"
      "db = sqlite3.connect(path); db.execute('create table x(a)'); "
      "db.commit(); db.close()\n"
      "open(marker, 'w').close()\n"
      "time.sleep(1.0)\n"
      "data = open(ref, 'rb').read()\n"
      "f.seek(0); f.truncate(); f.write(data); f.flush(); "
      "os.fsync(f.fileno())\n"
      "time.sleep(0.5)\n";
  {
    std::ofstream out(dir + "/writer.py");
    out << writer;
  }
  std::string line;
  for (const std::string& a : shard("0", dir + "/b")) line += " '" + a + "'";
  const auto held = testing::RunCommand(
      "/usr/bin/python3 " + dir + "/writer.py " + dir +
      "/b/shard-1-of-2.sqlite " + ref + " " + dir + "/locked & while [ ! -e " +
      dir + "/locked ]; do sleep 0.01; done; " + AIA_BINARY + line +
      "; rc=$?; wait; exit $rc");
  EXPECT_EQ(held.exit_code, 0) << held.err;
  fs::remove_all(dir);
}

TrainOptions TinyTraining(const std::string& data, const std::string& out) {
  TrainOptions t;
  t.data = {data};
  t.out = out;
  t.network.width = 8;
  t.network.hidden = 16;
  t.network.channels.window = 16;
  t.epochs = 4;
  t.batch = 8;
  t.lr = 3e-3;
  t.lr_min = 1e-4;
  t.val_share = 0.25;
  t.threads = 1;
  t.progress = false;
  return t;
}

// The one-line error Train refuses `t` with; "(not refused)" when it
// trains.
std::string TrainRefusal(const TrainOptions& t) {
  try {
    Train(t);
  } catch (const InputError& e) {
    return e.Format();
  }
  return "(not refused)";
}

// Whether Debian's python3-torch is there (tools/igbnet.py needs it).
bool PythonHasTorch() {
  return testing::RunCommand("/usr/bin/python3 -c 'import torch'").exit_code ==
         0;
}

// tools/igbnet.py loads `model` and reproduces `logits` from the `batch`
// images `x` of 16 x 16 pixels (files written into `dir`).
void ExpectPythonReproduces(const std::string& dir, const std::string& model,
                            const std::vector<float>& x,
                            const std::vector<float>& logits, int batch) {
  const auto write = [](const std::string& path, const std::vector<float>& v) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(v.data(), sizeof(float), v.size(), f);
    std::fclose(f);
  };
  write(dir + "/x.f32", x);
  write(dir + "/logits.f32", logits);
  const auto py = testing::RunCommand(
      "/usr/bin/python3 " + testing::SourcePath("tools/igbnet.py") + " check " +
      model + " " + dir + "/x.f32 " + std::to_string(batch) + " 16 16 " + dir +
      "/logits.f32");
  EXPECT_EQ(py.exit_code, 0) << py.out << py.err;
}

TEST(TrainTest, AFewStepsLowerTheLossAndAResumedRunEndsTheSame) {
  const std::string dir = testing::MakeTempDir("aia_train_");
  DatasetOptions d = Tiny(dir + "/data");
  d.episodes = 8;
  d.keep = 4;
  RunDataset(d);

  const std::vector<EpochLog> logs =
      Train(TinyTraining(dir + "/data", dir + "/a.pt"));
  ASSERT_EQ(logs.size(), 4u);
  EXPECT_LT(logs.back().train_loss, logs.front().train_loss);
  EXPECT_TRUE(fs::exists(dir + "/a.train.csv"));
  EXPECT_TRUE(fs::exists(dir + "/a.pt.ckpt"));

  TrainOptions b = TinyTraining(dir + "/data", dir + "/b.pt");
  b.stop_after_epochs = 2;
  EXPECT_EQ(Train(b).size(), 2u);
  b.stop_after_epochs = 0;
  b.resume = true;
  const std::vector<EpochLog> resumed = Train(b);
  ASSERT_EQ(resumed.size(), 4u);
  EXPECT_EQ(resumed.back().train_loss, logs.back().train_loss);
  EXPECT_EQ(resumed.back().val_acc, logs.back().val_acc);

  const auto na = IgbNet::Load(dir + "/a.pt", "a", 0, "k");
  const auto nb = IgbNet::Load(dir + "/b.pt", "b", 0, "k");
  std::vector<float> x(3 * kNumChannels * 16 * 16, 0.25f), la(12), lb(12);
  for (std::size_t i = 0; i < x.size(); i += 7) x[i] = 1.0f;
  na->Forward(x.data(), 3, 16, 16, la.data());
  nb->Forward(x.data(), 3, 16, 16, lb.data());
  EXPECT_EQ(la, lb);

  // A run killed after its last checkpoint and before its log: a resume of
  // the finished run writes the log as the checkpoint holds it.
  const std::string log = testing::ReadFile(dir + "/b.train.csv");
  WriteFileAtomic(dir + "/b.train.csv", log.substr(0, log.find('\n') + 1));
  EXPECT_EQ(Train(b).size(), 4u);
  EXPECT_EQ(testing::ReadFile(dir + "/b.train.csv"), log);

  // Resuming with other options is refused, the loss's options included.
  for (const auto& change : std::vector<void (*)(TrainOptions*)>{
           [](TrainOptions* o) { o->lr = 1e-2; },
           [](TrainOptions* o) { o->valid_moves = 1; },
           [](TrainOptions* o) { o->mistake_weight = 2.0; },
           [](TrainOptions* o) { o->ending_weight = 2.0; },
           // The weights depend on the thread count too.
           [](TrainOptions* o) { o->threads = 2; }}) {
    TrainOptions c = b;
    change(&c);
    EXPECT_THROW(Train(c), InputError);
  }
  // A dataset that grew since (its samples would count in some epochs and
  // not in others) is refused, and so is one that aia dataset is writing
  // (it holds the shard's lock).
  {
    TrainOptions c = TinyTraining(dir + "/data", dir + "/c.pt");
    c.stop_after_epochs = 1;
    Train(c);
    d.episodes = 10;
    RunDataset(d);
    c.stop_after_epochs = 0;
    c.resume = true;
    try {
      Train(c);
      ADD_FAILURE() << "a resume on grown data was taken";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("was written on other data"),
                std::string::npos)
          << e.what();
    }
    // This process's lock (it wrote `data` itself) does not count; another
    // process's does: flock(1) holds the shard of a dataset made apart
    // while aia train starts.
    ASSERT_EQ(testing::RunAia({"dataset", "--out", dir + "/data2", "--episodes",
                               "2", "--size", "3x3", "--quiet"})
                  .exit_code,
              0);
    const auto r =
        testing::RunCommand("flock -n " + dir + "/data2/shard-0-of-1.sqlite " +
                            std::string(AIA_BINARY) + " train --data " + dir +
                            "/data2 --out " + dir + "/e.pt --epochs 1");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("shard-0-of-1.sqlite: --data: is being written by "
                         "aia dataset (it holds the shard's lock)"),
              std::string::npos)
        << r.err;
  }

  // Python (Debian's python3-torch) loads the model and reproduces the C++
  // logits on the same input.
  if (!PythonHasTorch()) {
    fs::remove_all(dir);
    GTEST_SKIP() << "python3-torch is not installed";
  }
  ExpectPythonReproduces(dir, dir + "/a.pt", x, la, 3);

  // Files whose metadata does not match their tensors, or from another
  // format version, are bad input: one line, exit 2.
  const std::string craft =
      "/usr/bin/python3 -c \"import torch, json, sys\n"
      "m = torch.jit.load(sys.argv[1])\n"
      "meta = json.loads(bytes(m.aia_meta.tolist()).decode())\n"
      "meta[sys.argv[2]] = int(sys.argv[3])\n"
      "m.aia_meta = torch.tensor(list(json.dumps(meta).encode()), "
      "dtype=torch.uint8)\n"
      "m.save(sys.argv[4])\" ";
  const std::pair<std::string, std::string> cases[] = {
      {"width 16", "does not match the model's metadata"},
      {"version 99", "model format version 99"}};
  for (const auto& [change, message] : cases) {
    const std::string bad = dir + "/bad.pt";
    ASSERT_EQ(testing::RunCommand(craft + dir + "/a.pt " + change + " " + bad)
                  .exit_code,
              0);
    const auto r =
        testing::RunAia({"run", testing::SourcePath("scenarios/default.yaml"),
                         "--policy", "igbnet", "--set", "policy.model=" + bad,
                         "--out", dir + "/run", "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }

  fs::remove_all(dir);
}

}  // namespace
}  // namespace aia

namespace aia {
namespace {

// The geodesic channel (a fifth input): a model trained with it renders
// five channels from the dataset's states, is saved as format version 2,
// and Python reads it and reproduces its logits.
TEST(TrainTest, AGeodesicModelTrainsAndPythonReproducesIt) {
  const std::string dir = testing::MakeTempDir("aia_train_");
  DatasetOptions d = Tiny(dir + "/data");
  RunDataset(d);
  TrainOptions t = TinyTraining(dir + "/data", dir + "/g.pt");
  t.network.channels.geodesic = true;
  t.epochs = 2;
  const std::vector<EpochLog> logs = Train(t);
  ASSERT_EQ(logs.size(), 2u);
  const auto net = IgbNet::Load(dir + "/g.pt", "g", 0, "k");
  ASSERT_TRUE(net->config().channels.geodesic);
  ASSERT_EQ(net->config().channels.num_channels(), 5);
  std::vector<float> x(2 * 5 * 16 * 16, 0.1f), logits(8);
  for (std::size_t i = 0; i < x.size(); i += 5) x[i] = 0.9f;
  net->Forward(x.data(), 2, 16, 16, logits.data());
  if (!PythonHasTorch()) {
    fs::remove_all(dir);
    GTEST_SKIP() << "python3-torch is not installed";
  }
  ExpectPythonReproduces(dir, dir + "/g.pt", x, logits, 2);
  fs::remove_all(dir);
}

// One epoch of a model on DIR/data (DIR/plain.pt), then one epoch of the
// model `extend` makes of it (--init DIR/plain.pt; DIR/ext.pt), loaded.
std::unique_ptr<IgbNet> TrainExtended(
    const std::string& dir, const std::function<void(TrainOptions*)>& extend) {
  TrainOptions plain = TinyTraining(dir + "/data", dir + "/plain.pt");
  plain.epochs = 1;
  Train(plain);
  TrainOptions ext = TinyTraining(dir + "/data", dir + "/ext.pt");
  ext.init = dir + "/plain.pt";
  ext.epochs = 1;
  extend(&ext);
  EXPECT_EQ(Train(ext).size(), 1u);
  return IgbNet::Load(dir + "/ext.pt", "m", 0, "k");
}

// Message passing: a fresh model with two hops trains (its batches whole
// steps) and a stopped run resumes to the same model; a model without hops
// extends to one hop (--init, --message-hops 1) and trains on; cutting hops
// is refused; Python loads it and reproduces the logits of robots alone.
TEST(TrainTest, AMessagePassingModelTrainsResumesAndExtends) {
  const std::string dir = testing::MakeTempDir("aia_train_");
  DatasetOptions d = Tiny(dir + "/data");
  d.episodes = 6;
  RunDataset(d);
  TrainOptions t = TinyTraining(dir + "/data", dir + "/mp.pt");
  t.message_hops = 2;
  const std::vector<EpochLog> logs = Train(t);
  ASSERT_EQ(logs.size(), 4u);
  EXPECT_LT(logs.back().train_loss, logs.front().train_loss);
  EXPECT_EQ(IgbNet::Load(dir + "/mp.pt", "m", 0, "k")->config().message_hops,
            2);
  TrainOptions r = TinyTraining(dir + "/data", dir + "/mp_r.pt");
  r.message_hops = 2;
  r.stop_after_epochs = 1;
  Train(r);
  r.stop_after_epochs = 0;
  r.resume = true;
  EXPECT_EQ(Train(r).back().train_loss, logs.back().train_loss);

  EXPECT_EQ(TrainExtended(dir, [](TrainOptions* t) { t->message_hops = 1; })
                ->config()
                .message_hops,
            1);
  TrainOptions cut = TinyTraining(dir + "/data", dir + "/cut.pt");
  cut.init = dir + "/mp.pt";
  cut.message_hops = 1;
  {
    const std::string refusal = TrainRefusal(cut);
    EXPECT_NE(refusal.find("--message-hops: the --init model passes "
                           "messages over 2 hops"),
              std::string::npos)
        << refusal;
  }
  if (!PythonHasTorch()) {
    fs::remove_all(dir);
    GTEST_SKIP() << "python3-torch is not installed";
  }
  const auto net = IgbNet::Load(dir + "/mp.pt", "m", 0, "k");
  std::vector<float> x(2 * kNumChannels * 16 * 16, 0.2f), logits(8);
  for (std::size_t i = 0; i < x.size(); i += 3) x[i] = 0.7f;
  net->Forward(x.data(), 2, 16, 16, logits.data());
  ExpectPythonReproduces(dir, dir + "/mp.pt", x, logits, 2);
  fs::remove_all(dir);
}

// In mazes the robots miss targets (the prior's mean lies behind a wall):
// samples carry their search points (SearchPoints) and last moves, which
// read back as written. A model with the reach channel is redefined to read
// them over the whole workspace with a trail channel (--init, --reach-world
// 1, --search 1, --trail 1, and a sharper reach channel dimmed by the detour:
// --geodesic-length 2 --reach-detour 0.75) and trains on; --search or
// --reach-detour without --reach-world, and a length for a model without
// the reach channel, are refused.
TEST(TrainTest, SearchPointsAreRecordedAndAnInitModelLearnsToReadThem) {
  const std::string dir = testing::MakeTempDir("aia_train_");
  DatasetOptions d = Tiny(dir + "/data");
  d.episodes = 3;
  d.keep = 30;
  d.size = {5, 5};
  d.sets = {"workspace.obstacles.generator.type=maze",
            "workspace.size=[20,20]"};
  RunDataset(d);
  const Dataset data = ReadDataset({dir + "/data"}, "--data");
  long searched = 0;
  for (const DatasetSample& s : data.samples) {
    if (s.search.empty()) continue;
    ++searched;
    ASSERT_EQ(s.search.size(), s.targets.size());
    for (const auto& points : s.search)
      for (const Vec2& p : points)
        EXPECT_TRUE(p.allFinite() && p.x() >= 0.0 && p.x() <= 20.0);
  }
  EXPECT_GT(searched, 0);
  // Every robot's last lattice move is recorded (none at step 0).
  long moved = 0;
  for (const DatasetSample& s : data.samples) {
    if (s.step == 0) EXPECT_EQ(s.came, Move::kStay);
    moved += s.came != Move::kStay;
  }
  EXPECT_GT(moved, 0);
  TrainOptions plain = TinyTraining(dir + "/data", dir + "/plain.pt");
  plain.network.channels.geodesic = true;
  plain.epochs = 1;
  Train(plain);
  TrainOptions world = TinyTraining(dir + "/data", dir + "/world.pt");
  world.init = dir + "/plain.pt";
  world.reach_world = 1;
  world.search = 1;
  world.trail = 1;
  world.geodesic_length = 2.0;
  world.reach_detour = 0.75;
  world.neighbour_cap = 3;
  world.epochs = 1;
  ASSERT_EQ(Train(world).size(), 1u);
  const auto net = IgbNet::Load(dir + "/world.pt", "w", 0, "k");
  EXPECT_TRUE(net->config().channels.reach_world);
  EXPECT_TRUE(net->config().channels.search);
  EXPECT_EQ(net->config().channels.num_channels(), 6);
  EXPECT_EQ(IgbNet::Load(dir + "/plain.pt", "p", 0, "k")
                ->config()
                .channels.geodesic_length,
            5.0);
  EXPECT_EQ(net->config().channels.geodesic_length, 2.0);
  EXPECT_EQ(net->config().channels.reach_detour, 0.75);
  EXPECT_EQ(net->config().channels.neighbour_cap, 3);
  // A second reach channel is added after the trail; a broad reach channel
  // would then go in between, where the second's weights are: refused.
  TrainOptions second = TinyTraining(dir + "/data", dir + "/second.pt");
  second.init = dir + "/world.pt";
  second.reach_second = 1;
  second.epochs = 1;
  Train(second);
  const auto second_net = IgbNet::Load(dir + "/second.pt", "s", 0, "k");
  EXPECT_EQ(second_net->config().channels.second_channel(), 6);
  EXPECT_EQ(second_net->config().channels.neighbour_cap, 3);  // --init's
  TrainOptions between = TinyTraining(dir + "/data", dir + "/between.pt");
  between.init = dir + "/second.pt";
  between.reach_broad = 5.0;
  EXPECT_EQ(TrainRefusal(between),
            "command line: --init: the model's input channels (occupancy, "
            "own, neighbours, heat, reach, trail, second) would not keep "
            "their places among those asked for (occupancy, own, "
            "neighbours, heat, reach, trail, broad, second): a channel can "
            "be added after the last, or the last ones removed");
  TrainOptions lone = TinyTraining(dir + "/data", dir + "/lone.pt");
  lone.init = dir + "/plain.pt";
  lone.search = 1;
  {
    const std::string refusal = TrainRefusal(lone);
    EXPECT_NE(refusal.find("--search: needs --reach-world 1"),
              std::string::npos)
        << refusal;
  }
  TrainOptions blind = TinyTraining(dir + "/data", dir + "/blind.pt");
  blind.geodesic_length = 2.0;
  EXPECT_EQ(TrainRefusal(blind),
            "command line: --geodesic-length: needs the reach channel "
            "(--geodesic, or an --init model with it)");
  TrainOptions windowed = TinyTraining(dir + "/data", dir + "/windowed.pt");
  windowed.network.channels.geodesic = true;
  windowed.reach_detour = 1.0;
  EXPECT_EQ(TrainRefusal(windowed),
            "command line: --reach-detour: needs --reach-world 1");

  // --epochs 0: --init's weights written again with the channel settings
  // the flags change, no training (how the learned recipe's last step caps
  // the neighbours channel); without --init, refused.
  // A model's logits on fixed images (the same weights, the same logits).
  const auto logits = [](const IgbNet& model) {
    const int c = model.config().channels.num_channels();
    std::vector<float> x(2 * c * 16 * 16, 0.2f), out(8);
    for (std::size_t i = 0; i < x.size(); i += 3) x[i] = 0.7f;
    model.Forward(x.data(), 2, 16, 16, out.data());
    return out;
  };
  TrainOptions capped = TinyTraining(dir + "/data", dir + "/capped.pt");
  capped.init = dir + "/world.pt";
  capped.neighbour_cap = 2;
  capped.epochs = 0;
  EXPECT_TRUE(Train(capped).empty());
  const auto capped_net = IgbNet::Load(dir + "/capped.pt", "c", 0, "k");
  EXPECT_EQ(capped_net->config().channels.neighbour_cap, 2);
  EXPECT_EQ(capped_net->config().channels.reach_detour, 0.75);
  EXPECT_EQ(logits(*capped_net), logits(*net));
  EXPECT_FALSE(fs::exists(dir + "/capped.ckpt"));
  TrainOptions nothing = TinyTraining(dir + "/data", dir + "/nothing.pt");
  nothing.epochs = 0;
  EXPECT_EQ(TrainRefusal(nothing),
            "command line: --epochs: 0 writes the --init model again: "
            "needs --init");
  EXPECT_FALSE(fs::exists(dir + "/nothing.pt"));
  // Nor with --resume, nor over a model whose checkpoint is there (it would
  // describe another model, and a --resume from it keep this one).
  TrainOptions resumed = capped;
  resumed.resume = true;
  EXPECT_EQ(TrainRefusal(resumed),
            "command line: --resume: --epochs 0 trains nothing: there is "
            "nothing to resume; drop the flag");
  TrainOptions over = TinyTraining(dir + "/data", dir + "/world.pt");
  over.init = dir + "/plain.pt";
  over.epochs = 0;
  const std::string world_sha = Sha256Hex(ReadFile(dir + "/world.pt", 1 << 26));
  EXPECT_EQ(TrainRefusal(over),
            "command line: --out: '" + CheckpointPath(dir + "/world.pt") +
                "' is there (a training run of this model); "
                "--epochs 0 would write a model it does not "
                "describe beside it: remove it or choose "
                "another --out");
  EXPECT_EQ(Sha256Hex(ReadFile(dir + "/world.pt", 1 << 26)), world_sha);

  // tools/igbnet.py set: the same weights, channel parameters changed (how
  // the learned recipe's round 9 actor is made); bad input is one line and
  // exit 2, and writes nothing.
  if (!PythonHasTorch()) {
    fs::remove_all(dir);
    GTEST_SKIP() << "python3-torch is not installed";
  }
  const std::string set =
      "/usr/bin/python3 " + testing::SourcePath("tools/igbnet.py") + " set ";
  const auto ok = testing::RunCommand(set + dir + "/world.pt " + dir +
                                      "/set.pt reach_detour=0.25 "
                                      "geodesic_length=3 neighbour_cap=2");
  ASSERT_EQ(ok.exit_code, 0) << ok.out << ok.err;
  const auto changed = IgbNet::Load(dir + "/set.pt", "s", 0, "k");
  EXPECT_EQ(changed->config().channels.reach_detour, 0.25);
  EXPECT_EQ(changed->config().channels.geodesic_length, 3.0);
  EXPECT_EQ(changed->config().channels.neighbour_cap, 2);
  EXPECT_EQ(net->config().channels.neighbour_cap, 3);
  EXPECT_TRUE(changed->config().channels.search);
  EXPECT_EQ(logits(*changed), logits(*net));
  for (const auto& [args, error] :
       std::vector<std::pair<std::string, std::string>>{
           {"/world.pt " + dir + "/bad.pt reach=1",
            "error: command line: reach: not a settable channel parameter "
            "(geodesic_length, neighbour_cap, reach_detour)\n"},
           {"/world.pt " + dir + "/bad.pt neighbour_cap=1.5",
            "error: command line: neighbour_cap: must be a whole number, 0 "
            "(off) to 1000000; got '1.5'\n"},
           {"/world.pt " + dir + "/bad.pt reach_detour=-1",
            "error: command line: reach_detour: must be 0 (off) or above; got "
            "'-1'\n"},
           {"/world.pt " + dir + "/bad.pt geodesic_length=0",
            "error: command line: geodesic_length: must be above 0; got '0'\n"},
           {"/plain.pt " + dir + "/bad.pt reach_detour=0.5",
            "error: command line: reach_detour: needs a model whose reach "
            "channel covers the workspace (reach_world)\n"}}) {
    const auto bad = testing::RunCommand(set + dir + args);
    EXPECT_EQ(bad.exit_code, 2) << args;
    EXPECT_EQ(bad.err, error) << args;
  }
  EXPECT_FALSE(fs::exists(dir + "/bad.pt"));
  fs::remove_all(dir);
}

// The centre (fc1 reads the cells around the robot's): a model without one
// is extended by it (--init, --centre 3: window 16, 8 cells of the blocks'
// output) and trains on, and Python reproduces its logits; an even centre,
// one in the global frame, one beyond the blocks' output and a change of
// an --init model's centre are refused.
TEST(TrainTest, AModelIsExtendedByTheCellsAroundTheRobot) {
  const std::string dir = testing::MakeTempDir("aia_train_");
  RunDataset(Tiny(dir + "/data"));
  const auto net = TrainExtended(dir, [](TrainOptions* t) { t->centre = 3; });
  EXPECT_EQ(net->config().centre, 3);
  const auto refused = [&](const TrainOptions& t, const std::string& message) {
    EXPECT_EQ(TrainRefusal(t), "command line: --centre: " + message);
  };
  TrainOptions even = TinyTraining(dir + "/data", dir + "/even.pt");
  even.centre = 4;
  refused(even, "must be odd (the robot's cell in the middle)");
  TrainOptions global = TinyTraining(dir + "/data", dir + "/global.pt");
  global.centre = 3;
  global.network.channels.frame = ChannelFrame::kGlobal;
  refused(global, "needs the centred frame (frame: centred)");
  TrainOptions wide = TinyTraining(dir + "/data", dir + "/wide.pt");
  wide.centre = 9;
  refused(wide, "must be at most 7: the blocks' output is 8 cells per side");
  TrainOptions change = TinyTraining(dir + "/data", dir + "/change.pt");
  change.init = dir + "/ext.pt";
  change.centre = 5;
  refused(change,
          "the --init model reads a centre of 3 cells; it can be added to a "
          "model without one, not changed");
  if (!PythonHasTorch()) {
    fs::remove_all(dir);
    GTEST_SKIP() << "python3-torch is not installed";
  }
  std::vector<float> x(2 * kNumChannels * 16 * 16, 0.3f), logits(8);
  for (std::size_t i = 0; i < x.size(); i += 7) x[i] = 0.8f;
  net->Forward(x.data(), 2, 16, 16, logits.data());
  ExpectPythonReproduces(dir, dir + "/ext.pt", x, logits, 2);
  fs::remove_all(dir);
}

TEST(LearningCliTest, BadFlagsAreOneLineErrorsWithExitCode2) {
  const std::string dir = testing::MakeTempDir("aia_cli_");
  const std::pair<std::vector<std::string>, std::string> cases[] = {
      {{"dataset", "--out", dir, "--shard", "3/2"},
       "--shard: need 0 <= K < N, got 3/2"},
      {{"dataset", "--out", dir, "--size", "ten"},
       "--size: must be a size ROBOTSxTARGETS such as 10x10, got ten"},
      {{"dataset", "--out", dir, "--policy", "nope"}, "--policy: unknown"},
      {{"dataset", "--out", dir, "--set", "seed=3"},
       "--set seed: is also given by --first-seed"},
      {{"train", "--data", dir + "/none", "--out", dir + "/m.pt"},
       "no such file or folder"},
      {{"train", "--data", dir, "--out", dir + "/m.pt"}, "holds no dataset"},
      {{"train", "--data", dir, "--frame", "polar"},
       "--frame: must be global, centred or centered, got polar"},
      {{"train", "--data", dir, "--lr", "2"}, "--lr: must be"},
      // The flags are checked by the fields' declarations (the ranges the
      // model file's metadata is read with), in the scenario keys' form.
      {{"train", "--data", dir, "--window", "2"},
       "error: command line: --window: must be an integer in [4, 512], got 2"},
      {{"train", "--data", dir, "--lr", "0.01", "--lr-min", "0.1"},
       "error: command line: --lr-min: must be at most --lr"},
      // No default model file: the shipped one is never replaced by accident.
      {{"train", "--data", dir}, "--out: is required"},
      {{"train", "--data", dir, "--message-hops", "9"},
       "--message-hops: must be an integer in [-1, 8], got 9"},
      {{"train", "--data", dir, "--centre", "33"},
       "--centre: must be an integer in [-1, 31], got 33"},
      {{"train", "--data", dir, "--geodesic-length", "0"},
       "--geodesic-length: must be -1 (the default) or above 0"},
      {{"train", "--data", dir, "--reach-detour", "-0.5"},
       "--reach-detour: must be -1 (the default), 0 or above"},
      {{"train", "--data", dir, "--init", dir + "/none.pt", "--out",
        dir + "/m.pt"},
       "--init: '" + dir + "/none.pt': no such model file"},
      // The model read brings its network: its flags are not ignored but
      // refused.
      {{"train", "--data", dir, "--init", dir + "/none.pt", "--out",
        dir + "/m.pt", "--width", "64"},
       "error: command line: --width: the network is the one of the --init "
       "model"},
      {{"train", "--data", dir, "--validate", dir + "/none.pt", "--frame",
        "global"},
       "--frame: the network is the one of the --validate model"},
      // --validate trains nothing: the flags that would change a model
      // scored as it is were ignored.
      {{"train", "--data", dir, "--validate", dir + "/none.pt", "--trail", "1"},
       "error: command line: --trail: --validate trains nothing"},
      {{"train", "--data", dir, "--validate", dir + "/none.pt", "--epochs",
        "3"},
       "error: command line: --epochs: --validate trains nothing"},
      // One setting given twice: one would win silently.
      {{"dataset", "--out", dir, "--max-steps", "5", "--set",
        "mission.max_steps=50"},
       "error: command line: --set mission.max_steps: is also given by "
       "--max-steps"},
      {{"dataset", "--out", dir, "--policy", "igbnet", "--model",
        testing::SourcePath("models/igbnet.pt"), "--set",
        "policy.model=" + testing::SourcePath("models/igbnet_10x10.pt")},
       "error: command line: --set policy.model: is also given by --model"},
      {{"dataset", "--out", dir, "--set", "robots={count: 3}"},
       "error: command line: --set robots: replaces the whole section, and "
       "--size gives robots.count in it"},
      {{"dataset", "--out", dir, "--policy", "random", "--model",
        testing::SourcePath("models/igbnet.pt")},
       "error: command line: --model: policy random reads no model"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = testing::RunAia(args);
    EXPECT_EQ(r.exit_code, 2) << args[0] << " " << r.err;
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace aia
