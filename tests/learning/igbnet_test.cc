// The network behind its torch-free header and the igbnet policy: save and
// load give identical outputs; bad model files are bad input; relabelling
// the robots permutes the actions exactly; the step does not matter.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>

#include "aia/core/error.h"
#include "aia/core/hash.h"
#include "aia/core/io.h"
#include "aia/core/rng.h"
#include "aia/estimation/heatmap.h"
#include "aia/learning/igbnet_policy.h"
#include "aia/learning/network.h"
#include "aia/learning/scorer.h"
#include "aia/planning/information.h"
#include "support/team_fixture.h"
#include "support/test_support.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

NetworkConfig SmallConfig() {
  NetworkConfig c;
  c.width = 8;
  c.hidden = 16;
  c.channels.window = 16;
  return c;
}

std::vector<float> RandomImages(int batch, int h, int w, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<float> x(static_cast<std::size_t>(batch) * kNumChannels * h * w);
  for (float& v : x) v = static_cast<float>(rng.Uniform());
  return x;
}

TEST(IgbNetTest, SaveAndLoadGiveIdenticalOutputs) {
  const std::string dir = testing::MakeTempDir("aia_net_");
  for (ChannelFrame frame : {ChannelFrame::kCentred, ChannelFrame::kGlobal}) {
    NetworkConfig c = SmallConfig();
    c.channels.frame = frame;
    IgbNet net(c, 7);
    const std::vector<float> x = RandomImages(5, 20, 24, 3);
    std::vector<float> a(5 * kNumMoves), b(5 * kNumMoves);
    net.Forward(x.data(), 5, 20, 24, a.data());
    net.Save(dir + "/m.pt");
    const auto loaded = IgbNet::Load(dir + "/m.pt", "f", 0, "k");
    EXPECT_EQ(loaded->config().ToJson(), c.ToJson());
    loaded->Forward(x.data(), 5, 20, 24, b.data());
    EXPECT_EQ(a, b);
    // Batched and one at a time agree.
    std::vector<float> one(kNumMoves);
    const std::size_t image = static_cast<std::size_t>(kNumChannels) * 20 * 24;
    for (int i = 0; i < 5; ++i) {
      loaded->Forward(x.data() + i * image, 1, 20, 24, one.data());
      for (int m = 0; m < kNumMoves; ++m)
        EXPECT_NEAR(one[m], a[i * kNumMoves + m], 1e-5);
    }
  }
  fs::remove_all(dir);
}

// A network with a centre (fc1 also reads the 3 x 3 cells around the
// robot's) saves and loads to the same logits, batched or one at a time.
TEST(IgbNetTest, ACentreNetworkSavesAndLoadsToTheSameLogits) {
  const std::string dir = testing::MakeTempDir("aia_net_");
  NetworkConfig c = SmallConfig();
  c.centre = 3;
  IgbNet net(c, 7);
  const int side = c.channels.window;
  const std::vector<float> x = RandomImages(3, side, side, 5);
  std::vector<float> a(3 * kNumMoves), b(3 * kNumMoves), one(kNumMoves);
  net.Forward(x.data(), 3, side, side, a.data());
  net.Save(dir + "/m.pt");
  const auto loaded = IgbNet::Load(dir + "/m.pt", "f", 0, "k");
  EXPECT_EQ(loaded->config().centre, 3);
  loaded->Forward(x.data(), 3, side, side, b.data());
  EXPECT_EQ(a, b);
  const std::size_t image =
      static_cast<std::size_t>(kNumChannels) * side * side;
  for (int i = 0; i < 3; ++i) {
    loaded->Forward(x.data() + i * image, 1, side, side, one.data());
    for (int m = 0; m < kNumMoves; ++m)
      EXPECT_NEAR(one[m], a[i * kNumMoves + m], 1e-5);
  }
  fs::remove_all(dir);
}

TEST(IgbNetTest, MissingOrCorruptModelIsBadInput) {
  const std::string dir = testing::MakeTempDir("aia_net_");
  try {
    IgbNet::Load(dir + "/none.pt", "s.yaml", 4, "policy.model");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Format().rfind("s.yaml:4: policy.model: '", 0), 0u)
        << e.Format();
    EXPECT_NE(e.Format().find("no such model file"), std::string::npos);
  }
  std::ofstream(dir + "/text.pt") << "not a model\n";
  try {
    IgbNet::Load(dir + "/text.pt", "s.yaml", 4, "policy.model");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(e.Format().find("not a readable model"), std::string::npos)
        << e.Format();
    EXPECT_EQ(e.Format().find('\n'), std::string::npos) << e.Format();
  }
  // A valid model cut short.
  IgbNet(SmallConfig(), 1).Save(dir + "/m.pt");
  fs::resize_file(dir + "/m.pt", fs::file_size(dir + "/m.pt") / 2);
  EXPECT_THROW(IgbNet::Load(dir + "/m.pt", "s.yaml", 4, "policy.model"),
               InputError);
  fs::remove_all(dir);
}

TEST(IgbNetTest, MetadataRoundTripsAndRejectsNonsense) {
  NetworkConfig c = SmallConfig();
  c.channels.frame = ChannelFrame::kGlobal;
  c.channels.cell = 0.25;
  const NetworkConfig back = NetworkConfig::FromJson(c.ToJson());
  EXPECT_EQ(back.ToJson(), c.ToJson());
  EXPECT_THROW(NetworkConfig::FromJson("{"), std::runtime_error);
  EXPECT_THROW(NetworkConfig::FromJson(R"({"format": "other"})"),
               std::runtime_error);
  std::string j = c.ToJson();
  j.replace(j.find("\"width\":8"), 9, "\"width\":-3");
  EXPECT_THROW(NetworkConfig::FromJson(j), std::runtime_error);
  // Without the geodesic channel a model is written as version 1 (readable
  // by builds before it); with it, version 2.
  EXPECT_NE(c.ToJson().find("\"version\":1"), std::string::npos);
  EXPECT_EQ(c.ToJson().find("geodesic"), std::string::npos);
  NetworkConfig g = SmallConfig();
  g.channels.geodesic = true;
  g.channels.geodesic_length = 7.5;
  const NetworkConfig gb = NetworkConfig::FromJson(g.ToJson());
  EXPECT_TRUE(gb.channels.geodesic);
  EXPECT_EQ(gb.channels.geodesic_length, 7.5);
  EXPECT_EQ(gb.channels.num_channels(), 5);
  EXPECT_NE(g.ToJson().find("\"version\":2"), std::string::npos);
  // Message passing: version 3, hops 0..8.
  NetworkConfig mp = g;
  mp.message_hops = 3;
  EXPECT_NE(mp.ToJson().find("\"version\":3"), std::string::npos);
  EXPECT_EQ(NetworkConfig::FromJson(mp.ToJson()).message_hops, 3);
  EXPECT_EQ(NetworkConfig::FromJson(g.ToJson()).message_hops, 0);
  std::string hops = mp.ToJson();
  hops.replace(hops.find("\"message_hops\":3"), 16, "\"message_hops\":9");
  EXPECT_THROW(NetworkConfig::FromJson(hops), std::runtime_error);
  // The reach channel over the world, and from search points: version 4;
  // each needs the one before it.
  NetworkConfig world = g;
  world.channels.reach_world = true;
  world.channels.search = true;
  EXPECT_NE(world.ToJson().find("\"version\":4"), std::string::npos);
  const NetworkConfig wb = NetworkConfig::FromJson(world.ToJson());
  EXPECT_TRUE(wb.channels.reach_world);
  EXPECT_TRUE(wb.channels.search);
  EXPECT_EQ(g.ToJson().find("reach_world"), std::string::npos);
  std::string no_world = world.ToJson();
  no_world.replace(no_world.find("\"reach_world\":true"), 18,
                   "\"reach_world\":false");
  try {
    NetworkConfig::FromJson(no_world);
    ADD_FAILURE() << "search without reach_world read";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "metadata: search: needs reach_world");
  }
  // The reach channel's detour: version 6, needs reach_world.
  NetworkConfig detour = world;
  detour.channels.reach_detour = 0.5;
  EXPECT_NE(detour.ToJson().find("\"version\":6"), std::string::npos);
  EXPECT_EQ(NetworkConfig::FromJson(detour.ToJson()).channels.reach_detour,
            0.5);
  EXPECT_EQ(world.ToJson().find("reach_detour"), std::string::npos);
  std::string no_world_detour = detour.ToJson();
  no_world_detour.replace(no_world_detour.find("\"reach_world\":true"), 18,
                          "\"reach_world\":false");
  no_world_detour.replace(no_world_detour.find("\"search\":true"), 13,
                          "\"search\":false");
  try {
    NetworkConfig::FromJson(no_world_detour);
    ADD_FAILURE() << "reach_detour without reach_world read";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "metadata: reach_detour: needs reach_world");
  }
  // The broad reach channel: version 7, one more channel, needs reach_world.
  NetworkConfig broad = detour;
  broad.channels.reach_broad = 5.0;
  EXPECT_NE(broad.ToJson().find("\"version\":7"), std::string::npos);
  EXPECT_EQ(NetworkConfig::FromJson(broad.ToJson()).channels.reach_broad, 5.0);
  EXPECT_EQ(broad.channels.num_channels(), detour.channels.num_channels() + 1);
  EXPECT_EQ(detour.ToJson().find("reach_broad"), std::string::npos);
  std::string no_world_broad = broad.ToJson();
  no_world_broad.replace(no_world_broad.find("\"reach_world\":true"), 18,
                         "\"reach_world\":false");
  no_world_broad.replace(no_world_broad.find("\"search\":true"), 13,
                         "\"search\":false");
  no_world_broad.replace(no_world_broad.find("\"reach_detour\":0.5"), 18,
                         "\"reach_detour\":0.0");
  try {
    NetworkConfig::FromJson(no_world_broad);
    ADD_FAILURE() << "reach_broad without reach_world read";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "metadata: reach_broad: needs reach_world");
  }
  // The second reach channel: version 8, one more channel, needs reach_world.
  NetworkConfig second = broad;
  second.channels.reach_second = true;
  EXPECT_NE(second.ToJson().find("\"version\":8"), std::string::npos);
  EXPECT_TRUE(NetworkConfig::FromJson(second.ToJson()).channels.reach_second);
  EXPECT_EQ(second.channels.num_channels(), broad.channels.num_channels() + 1);
  EXPECT_EQ(second.channels.second_channel(),
            broad.channels.broad_channel() + 1);
  EXPECT_EQ(broad.ToJson().find("reach_second"), std::string::npos);
  std::string no_world_second = second.ToJson();
  for (const auto& [from, to] :
       std::vector<std::pair<std::string, std::string>>{
           {"\"reach_world\":true", "\"reach_world\":false"},
           {"\"search\":true", "\"search\":false"},
           {"\"reach_detour\":0.5", "\"reach_detour\":0.0"},
           {"\"reach_broad\":5.0", "\"reach_broad\":0.0"}})
    no_world_second.replace(no_world_second.find(from), from.size(), to);
  try {
    NetworkConfig::FromJson(no_world_second);
    ADD_FAILURE() << "reach_second without reach_world read";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "metadata: reach_second: needs reach_world");
  }
  // The neighbours channel's cap: version 9, with or without the reach
  // channel; not written when 0.
  for (const NetworkConfig& base : {g, second}) {
    NetworkConfig capped = base;
    capped.channels.neighbour_cap = 2;
    EXPECT_NE(capped.ToJson().find("\"version\":9"), std::string::npos);
    EXPECT_NE(capped.ToJson().find("\"neighbour_cap\":2"), std::string::npos);
    EXPECT_EQ(NetworkConfig::FromJson(capped.ToJson()).channels.neighbour_cap,
              2);
    EXPECT_EQ(base.ToJson().find("neighbour_cap"), std::string::npos);
    EXPECT_EQ(capped.channels.num_channels(), base.channels.num_channels());
  }
  // The centre: version 5, odd, in the centred frame, within the blocks'
  // output (window 16, stride 2: 8 cells, the robot's cell 4).
  NetworkConfig centre = g;
  centre.centre = 3;
  EXPECT_NE(centre.ToJson().find("\"version\":5"), std::string::npos);
  EXPECT_EQ(NetworkConfig::FromJson(centre.ToJson()).centre, 3);
  EXPECT_EQ(g.ToJson().find("\"centre\""), std::string::npos);
  EXPECT_EQ(centre.FeatureSide(), 8);
  EXPECT_EQ(centre.CentreStart(), 3);
  const auto problem = [&](int cells, ChannelFrame frame) {
    NetworkConfig c = centre;
    c.centre = cells;
    c.channels.frame = frame;
    std::string json = centre.ToJson();
    json.replace(json.find("\"centre\":3"), 10,
                 "\"centre\":" + std::to_string(cells));
    if (frame == ChannelFrame::kGlobal)
      json.replace(json.find("\"centred\""), 9, "\"global\"");
    try {
      NetworkConfig::FromJson(json);
      ADD_FAILURE() << json << " read";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(e.what(), "metadata: centre: " + c.CentreProblem());
    }
    return c.CentreProblem();
  };
  EXPECT_EQ(problem(4, ChannelFrame::kCentred),
            "must be odd (the robot's cell in the middle)");
  EXPECT_EQ(problem(3, ChannelFrame::kGlobal),
            "needs the centred frame (frame: centred)");
  // Cells 4 - 4 .. 4 + 4 would reach row 8 of rows 0..7: at most 7.
  EXPECT_EQ(problem(9, ChannelFrame::kCentred),
            "must be at most 7: the blocks' output is 8 cells per side");
  std::string future = mp.ToJson();
  future.replace(future.find("\"version\":3"), 11, "\"version\":10");
  try {
    NetworkConfig::FromJson(future);
    ADD_FAILURE() << "version 10 read";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "model format version 10, this build reads 1 to 9");
  }
  // A version that is no integer, or none: said as it is (both read as
  // "version -1" before).
  const auto version_error = [&](const std::string& to) {
    std::string json = mp.ToJson();
    json.replace(json.find("\"version\":3"), 11, to);
    try {
      NetworkConfig::FromJson(json);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("read");
  };
  EXPECT_EQ(version_error("\"version\":2.5"),
            "metadata: version: must be an integer in [1, 9], got 2.5");
  EXPECT_EQ(version_error("\"version\":\"3\""),
            "metadata: version: must be an integer in [1, 9], got \"3\"");
  EXPECT_EQ(version_error("\"vers\":3"), "metadata: version: is missing");
  // 2^32 + 3 is no version 3 (an int would wrap to it).
  EXPECT_EQ(version_error("\"version\":4294967299"),
            "model format version 4294967299, this build reads 1 to 9");
}

// The metadata is read through NetworkConfig's declarations (the ranges
// `aia train` checks its flags against): errors name the key.
TEST(IgbNetTest, MetadataErrorsNameTheKeyAndItsDeclaredRange) {
  const auto error = [](std::string json, const std::string& from,
                        const std::string& to) {
    json.replace(json.find(from), from.size(), to);
    try {
      NetworkConfig::FromJson(json);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string j = SmallConfig().ToJson();
  EXPECT_EQ(error(j, "\"width\":8", "\"width\":-3"),
            "metadata: width: must be an integer in [1, 512], got -3");
  EXPECT_EQ(error(j, "\"window\":16", "\"window\":2"),
            "metadata: window: must be an integer in [4, 512], got 2");
  EXPECT_EQ(error(j, "\"frame\":\"centred\"", "\"frame\":\"polar\""),
            "metadata: frame: must be global, centred or centered, got polar");
  EXPECT_EQ(error(j, "\"width\":8,", ""), "metadata: width: is missing");
  EXPECT_EQ(error(j, "\"width\":8", "\"width\":8,\"depth\":2"),
            "metadata: depth: unknown key; valid top-level keys: frame, "
            "cell, window, blur, cutoff, geodesic, geodesic_length, "
            "observe_range, reach_margin, reach_world, search, "
            "reach_detour, trail, reach_broad, reach_second, "
            "neighbour_cap, width, stem_stride, pool, hidden, centre, "
            "message_hops");
}

// Inference runs a batch of two or more on oneDNN's own tensors, with the
// weights reordered once (torch_net.h, FoldedNet): the logits are bit for
// bit those of the same convolutions on plain tensors, which ATen runs
// through the same oneDNN kernels with a reorder around each, for the
// shipped models and a small network of another shape (an odd pooled
// grid), at batch sizes 2 to 33; a batch of one takes ATen's own way
// either way.
TEST(IgbNetTest, TheOneDnnTensorsGiveThePlainConvolutionsLogits) {
  std::vector<std::unique_ptr<IgbNet>> nets;
  for (const char* name : {"igbnet", "igbnet_learned", "igbnet_10x10"})
    nets.push_back(IgbNet::Load(
        std::string(AIA_SOURCE_DIR) + "/models/" + name + ".pt", "f", 0, "k"));
  NetworkConfig small = SmallConfig();
  small.pool = 3;
  nets.push_back(std::make_unique<IgbNet>(small, 11));
  for (const auto& net : nets) {
    const int side = net->config().channels.window;
    const int channels = net->config().channels.num_channels();
    for (int batch : {1, 2, 3, 33}) {
      Rng rng(static_cast<std::uint64_t>(batch));
      std::vector<float> x(static_cast<std::size_t>(batch) * channels * side *
                           side);
      for (float& v : x) v = rng.Uniform() < 0.8 ? 0.0f : rng.Uniform();
      std::vector<float> fast(batch * kNumMoves), plain(batch * kNumMoves);
      net->Forward(x.data(), batch, side, side, fast.data());
      {
        const internal::PlainConvolutions reference;
        net->Forward(x.data(), batch, side, side, plain.data());
      }
      EXPECT_EQ(fast, plain) << channels << " channels, batch " << batch;
    }
  }
}

// policy.precision: auto is bfloat16 only for teams of kBFloat16Team robots
// or more, and only where the CPU multiplies bfloat16 natively; bfloat16
// itself is refused where it does not.
TEST(IgbNetTest, PrecisionAutoIsBFloat16ForLargeTeamsWhereTheCpuHasIt) {
  EXPECT_FALSE(UsesBFloat16(Precision::kFloat32, 1000));
  EXPECT_FALSE(UsesBFloat16(Precision::kAuto, kBFloat16Team - 1));
  EXPECT_EQ(UsesBFloat16(Precision::kAuto, kBFloat16Team), NativeBFloat16());
  EXPECT_EQ(PrecisionProblem(Precision::kAuto), "");
  EXPECT_EQ(PrecisionProblem(Precision::kFloat32), "");
  if (NativeBFloat16()) {
    EXPECT_EQ(PrecisionProblem(Precision::kBFloat16), "");
    EXPECT_TRUE(UsesBFloat16(Precision::kBFloat16, 1));
  } else {
    EXPECT_NE(PrecisionProblem(Precision::kBFloat16).find("no native bfloat16"),
              std::string::npos);
    EXPECT_THROW(UsesBFloat16(Precision::kBFloat16, 1), std::runtime_error);
  }
}

// The bfloat16 convolutions give the float32 logits to bfloat16's precision
// (8 bits of mantissa, sums in float32): on images of the kinds the channels
// make, each logit within 2 % of the logits' range, and the same most
// probable move wherever the float32 one leads the next by more than that.
TEST(IgbNetTest, BFloat16LogitsAreTheFloat32OnesToItsPrecision) {
  if (!NativeBFloat16()) GTEST_SKIP() << "no native bfloat16 on this CPU";
  for (const char* name : {"igbnet", "igbnet_learned"}) {
    const auto net = IgbNet::Load(
        std::string(AIA_SOURCE_DIR) + "/models/" + name + ".pt", "f", 0, "k");
    const int side = net->config().channels.window;
    const int channels = net->config().channels.num_channels();
    const int batch = 64;
    Rng rng(5);
    std::vector<float> x(static_cast<std::size_t>(batch) * channels * side *
                         side);
    for (float& v : x) v = rng.Uniform() < 0.8 ? 0.0f : rng.Uniform();
    std::vector<float> f32(batch * kNumMoves), bf16(batch * kNumMoves);
    net->Forward(x.data(), batch, side, side, f32.data());
    net->Forward(x.data(), batch, side, side, bf16.data(), true);
    EXPECT_NE(f32, bf16) << name << ": bfloat16 was not used";
    const auto [lo, hi] = std::minmax_element(f32.begin(), f32.end());
    const float tolerance = 0.02f * (*hi - *lo);
    int led = 0;
    for (int b = 0; b < batch; ++b) {
      const float* a = f32.data() + b * kNumMoves;
      const float* c = bf16.data() + b * kNumMoves;
      for (int m = 0; m < kNumMoves; ++m)
        EXPECT_NEAR(a[m], c[m], tolerance) << name << " image " << b;
      std::vector<float> sorted(a, a + kNumMoves);
      std::sort(sorted.begin(), sorted.end());
      if (sorted[kNumMoves - 1] - sorted[kNumMoves - 2] <= 2 * tolerance)
        continue;
      ++led;
      EXPECT_EQ(std::max_element(a, a + kNumMoves) - a,
                std::max_element(c, c + kNumMoves) - c)
          << name << " image " << b;
    }
    EXPECT_GT(led, batch / 2) << name;
  }
}

// Each shipped model written again is the same file, byte for byte: the
// metadata written through the declarations is what the older writer wrote.
TEST(IgbNetTest, TheShippedModelsSavedAgainAreTheSameFiles) {
  const std::string dir = testing::MakeTempDir("aia_net_");
  // (igbnet_10x10.pt is of an older format, which Save does not write.)
  for (const char* name : {"igbnet", "igbnet_learned"}) {
    const std::string shipped =
        std::string(AIA_SOURCE_DIR) + "/models/" + name + ".pt";
    const auto net = IgbNet::Load(shipped, "f", 0, "k");
    net->Save(dir + "/again.pt");
    EXPECT_EQ(Sha256Hex(ReadFile(dir + "/again.pt", 1 << 26)),
              Sha256Hex(ReadFile(shipped, 1 << 26)))
        << name;
  }
  // The learned model sees the whole workspace's reach, the search points
  // and the trail, and its neighbours at most 2 a pixel (docs/learning.md,
  // Learned coordination); the default counts them.
  const auto learned = IgbNet::Load(
      std::string(AIA_SOURCE_DIR) + "/models/igbnet_learned.pt", "f", 0, "k");
  EXPECT_TRUE(learned->config().channels.reach_world);
  EXPECT_TRUE(learned->config().channels.search);
  EXPECT_TRUE(learned->config().channels.trail);
  EXPECT_EQ(learned->config().channels.neighbour_cap, 2);
  EXPECT_EQ(IgbNet::Load(std::string(AIA_SOURCE_DIR) + "/models/igbnet.pt", "f",
                         0, "k")
                ->config()
                .channels.neighbour_cap,
            0);
  fs::remove_all(dir);
}

// A path 0 - 1 - 2 - 3 and robot 4 alone, as a TeamGraph under the
// relabelling `perm` (robot k of the relabelled team is robot perm[k]).
TeamGraph PathGraph(const std::vector<int>& perm) {
  const std::vector<std::vector<int>> edges = {{1}, {0, 2}, {1, 3}, {2}, {}};
  std::vector<int> label(perm.size());
  for (std::size_t k = 0; k < perm.size(); ++k) label[perm[k]] = k;
  TeamGraph g;
  for (std::size_t k = 0; k < perm.size(); ++k) {
    for (int j : edges[perm[k]]) g.neighbours.push_back(label[j]);
    g.offsets.push_back(static_cast<int>(g.neighbours.size()));
  }
  return g;
}

// Message passing over K = 2 hops: a robot's logits depend on the robots
// within two links and on no other (changing robot 3 changes robots 1, 2
// and 3, not 0 nor 4); a robot alone gets Forward's logits; relabelling the
// robots permutes the logits; the same call twice gives the same numbers
// (no state, no notion of time); save and load keep it.
TEST(IgbNetTest, MessagePassingIsLocalEquivariantAndStateless) {
  NetworkConfig c = SmallConfig();
  c.message_hops = 2;
  IgbNet net(c, 5);
  const int n = 5, h = 16, w = 16;
  const std::size_t image = static_cast<std::size_t>(kNumChannels) * h * w;
  const std::vector<int> identity = {0, 1, 2, 3, 4};
  const auto logits_of = [&](const IgbNet& m, const std::vector<float>& x,
                             const TeamGraph& g) {
    std::vector<float> z(n * c.hidden), l(n * kNumMoves);
    m.Embed(x.data(), n, h, w, z.data());
    m.Head(z.data(), g, l.data());
    return l;
  };
  const auto row = [](const std::vector<float>& l, int i) {
    return std::vector<float>(l.begin() + i * kNumMoves,
                              l.begin() + (i + 1) * kNumMoves);
  };
  const std::vector<float> x = RandomImages(n, h, w, 9);
  const std::vector<float> a = logits_of(net, x, PathGraph(identity));
  EXPECT_EQ(a, logits_of(net, x, PathGraph(identity)));

  std::vector<float> alone(n * kNumMoves);
  net.Forward(x.data(), n, h, w, alone.data());
  for (int m = 0; m < kNumMoves; ++m)
    EXPECT_NEAR(a[4 * kNumMoves + m], alone[4 * kNumMoves + m], 1e-5);
  EXPECT_NE(row(a, 1), row(alone, 1));  // the messages do change robot 1

  std::vector<float> y = x;
  for (std::size_t v = 3 * image; v < 4 * image; ++v) y[v] = 1.0f - y[v];
  const std::vector<float> b = logits_of(net, y, PathGraph(identity));
  EXPECT_EQ(row(b, 0), row(a, 0));
  EXPECT_EQ(row(b, 4), row(a, 4));
  for (int i : {1, 2, 3}) EXPECT_NE(row(b, i), row(a, i)) << "robot " << i;

  const std::vector<int> perm = {3, 0, 4, 1, 2};
  std::vector<float> px(x.size());
  for (int k = 0; k < n; ++k)
    std::copy(x.begin() + perm[k] * image, x.begin() + (perm[k] + 1) * image,
              px.begin() + k * image);
  const std::vector<float> p = logits_of(net, px, PathGraph(perm));
  for (int k = 0; k < n; ++k)
    for (int m = 0; m < kNumMoves; ++m)
      EXPECT_NEAR(p[k * kNumMoves + m], a[perm[k] * kNumMoves + m], 1e-5);

  const std::string dir = testing::MakeTempDir("aia_net_");
  net.Save(dir + "/mp.pt");
  const auto loaded = IgbNet::Load(dir + "/mp.pt", "f", 0, "k");
  EXPECT_EQ(loaded->config().message_hops, 2);
  EXPECT_EQ(logits_of(*loaded, x, PathGraph(identity)), a);
  fs::remove_all(dir);
}

// The paper's configuration, as earlier builds wrote it (format version 1,
// four channels, no geodesic keys), loads and runs unchanged.
TEST(IgbNetTest, AModelOfAnEarlierBuildLoads) {
  const auto net = IgbNet::Load(testing::SourcePath("models/igbnet_10x10.pt"),
                                "m", 0, "policy.model");
  EXPECT_FALSE(net->config().channels.geodesic);
  EXPECT_EQ(net->config().channels.num_channels(), 4);
  const int w = net->config().channels.window;
  std::vector<float> x(static_cast<std::size_t>(kNumChannels) * w * w, 0.0f),
      logits(kNumMoves);
  net->Forward(x.data(), 1, w, w, logits.data());
  for (float l : logits) EXPECT_TRUE(std::isfinite(l));
}

// Four robots, three targets; each robot's belief made its own so that the
// robots see different things.
const char* kTeam = R"(
workspace: {size: [8, 8], obstacles: {boxes: [{center: [4, 4], size: [1, 1]}]}}
robots: {count: 4, step: 0.5, start: [[1.25, 1.25], [6.25, 1.75], [2.75, 6.25], [6.75, 6.75]]}
targets: {count: 3}
sensor: {range: 2.0}
communication: {mode: range, range: 6.0}
)";

void Personalize(testing::TeamFixture* f) {
  for (int i = 0; i < f->beliefs.rows(); ++i)
    for (int k = 0; k < f->layout.num_targets(); ++k) {
      f->beliefs.Omega(i, k) *= 1.0 + 3.0 * ((i * 7 + k * 3) % 5);
      f->beliefs.Xi(i, k) *= 1.0 + 3.0 * ((i * 7 + k * 3) % 5);
    }
}

// A policy's counter by name (-1: none of that name).
long Counter(const Policy& policy, const std::string& name) {
  for (const auto& [key, value] : policy.Counters())
    if (key == name) return value;
  return -1;
}

// The moves the robots made between the positions a test puts them at, as
// an episode records them (DecisionContext::history), per policy.
struct Trail {
  MoveHistory history;
  std::vector<int> last;  // the positions at the last decision
};
std::map<const IgbNetPolicy*, Trail>& Trails() {
  static std::map<const IgbNetPolicy*, Trail> trails;
  return trails;
}

// The team's context as a distributed policy is given it, with `prior`.
DecisionContext TeamContext(const testing::TeamFixture& f,
                            const std::vector<double>& prior) {
  DecisionContext ctx = f.Context();
  ctx.central = nullptr;
  ctx.log_det_prior = &prior;
  return ctx;
}

// One decision; `reset` starts a new episode first (the policy forgets).
// Between two decisions each robot made the lattice move from its last
// position to this one (none where it is not a neighbour).
std::vector<Move> Decide(IgbNetPolicy* policy, const testing::TeamFixture& f,
                         int step, const std::vector<double>& prior,
                         bool reset = true) {
  Trail& trail = Trails()[policy];
  const int n = f.world.NumRobots();
  if (reset || trail.history.num_robots() != n) {
    trail.history.Reset(n);
    trail.last = f.positions;
  }
  for (int i = 0; i < n; ++i)
    trail.history.Record(
        i, MoveBetween(f.world.map.lattice(), trail.last[i], f.positions[i]));
  trail.last = f.positions;
  DecisionContext ctx = TeamContext(f, prior);
  ctx.step = step;
  ctx.history = &trail.history;
  std::vector<Move> moves(n);
  if (reset) policy->Reset(f.world.map, n, f.world.NumTargets(), 1);
  policy->Decide(ctx, &moves);
  return moves;
}

std::shared_ptr<const IgbNet> TestNet(ChannelFrame frame, bool geodesic = false,
                                      int hops = 0) {
  NetworkConfig c = SmallConfig();
  c.channels.frame = frame;
  c.channels.cell = 0.5;
  c.channels.geodesic = geodesic;
  c.message_hops = hops;
  return std::make_shared<const IgbNet>(c, 11);
}

// With message passing (the last two cases) the logits agree to rounding:
// a robot's neighbours are summed in another order.
TEST(IgbNetPolicyTest, RelabellingTheRobotsPermutesTheActions) {
  struct Case {
    ChannelFrame frame;
    bool geodesic;
    int hops;
  };
  for (const auto& [frame, geodesic, hops] :
       std::vector<Case>{{ChannelFrame::kCentred, false, 0},
                         {ChannelFrame::kGlobal, false, 0},
                         {ChannelFrame::kCentred, true, 0},
                         {ChannelFrame::kGlobal, true, 0},
                         {ChannelFrame::kCentred, true, 1},
                         {ChannelFrame::kCentred, true, 2}}) {
    testing::TeamFixture f(kTeam);
    Personalize(&f);
    const std::vector<double> prior(3, std::log(1.0));
    IgbNetPolicy policy(TestNet(frame, geodesic, hops));
    const std::vector<Move> moves = Decide(&policy, f, 0, prior);
    const std::vector<float> logits = policy.logits();

    // Robot k of the relabelled team is robot perm[k] of the original.
    const std::vector<int> perm = {2, 0, 3, 1};
    testing::TeamFixture g(kTeam);
    Personalize(&g);
    BeliefSet permuted = g.beliefs;
    for (int k = 0; k < 4; ++k) {
      g.positions[k] = f.positions[perm[k]];
      permuted.CopyRow(k, f.beliefs, perm[k]);
    }
    g.beliefs = permuted;
    std::vector<Vec2> p;
    for (int idx : g.positions) p.push_back(g.world.map.lattice().Point(idx));
    g.comm.Update(1, p);
    IgbNetPolicy policy2(TestNet(frame, geodesic, hops));
    const std::vector<Move> moved = Decide(&policy2, g, 0, prior);
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(moved[k], moves[perm[k]]) << "robot " << k;
      for (int m = 0; m < kNumMoves; ++m) {
        const float got = policy2.logits()[k * kNumMoves + m],
                    want = logits[perm[k] * kNumMoves + m];
        if (hops == 0) {
          EXPECT_EQ(got, want);
        } else {
          EXPECT_NEAR(got, want, 1e-5);
        }
      }
    }
    if (hops > 0) {  // the messages matter: without them the logits differ
      IgbNetPolicy alone(TestNet(frame, geodesic, 0));
      Decide(&alone, f, 0, prior);
      EXPECT_NE(alone.logits(), logits);
    }
    // Not a degenerate network: the robots do not all agree.
    EXPECT_NE(std::vector<float>(logits.begin(), logits.begin() + 4),
              std::vector<float>(logits.begin() + 4, logits.begin() + 8));
  }
}

// The scorer skips the rows the view marks unread (robots the rules' walk
// moves): their logits are 0 and every other row's are, bit for bit, those
// of scoring the whole team, in a smaller batch or alone (robot 1 alone in
// its chunk of four goes as a batch of two copies). A model that passes
// messages needs every robot's features, so it scores every row.
TEST(IgbNetPolicyTest, UnreadRowsAreSkippedAndTheOthersScoreAsInTheWholeTeam) {
  for (const int hops : {0, 1}) {
    testing::TeamFixture f(kTeam);
    Personalize(&f);
    const std::vector<double> prior(3, std::log(1.0));
    const DecisionContext ctx = TeamContext(f, prior);
    NetworkScorer scorer(TestNet(ChannelFrame::kCentred, true, hops));
    scorer.Reset(f.world.map, 4, f.world.NumTargets());
    ScoringRows team;
    team.rows = {0, 1, 2, 3};
    team.row_of = {0, 1, 2, 3};
    std::vector<float> whole(4 * kNumMoves, -1.0f);
    scorer.Score(ctx, team, ScorerView{}, whole.data());
    for (const std::vector<std::uint8_t>& unread :
         {std::vector<std::uint8_t>{0, 1, 0, 0},
          std::vector<std::uint8_t>{1, 0, 1, 1},
          std::vector<std::uint8_t>{1, 1, 1, 1}}) {
      ScorerView view;
      view.unread = &unread;
      std::vector<float> got(4 * kNumMoves, -1.0f);
      scorer.Score(ctx, team, view, got.data());
      for (int b = 0; b < 4; ++b)
        for (int a = 0; a < kNumMoves; ++a) {
          const float want =
              hops == 0 && unread[b] ? 0.0f : whole[b * kNumMoves + a];
          EXPECT_EQ(got[b * kNumMoves + a], want)
              << "hops " << hops << ", row " << b << ", move " << a;
        }
    }
  }
}

// A scorer told the same knowledge stamp keeps the team's heatmaps only for
// the same rows: a team of other rows (a robot fewer) scores as a fresh
// scorer does, and the first team again as the first time.
TEST(IgbNetPolicyTest, TheSameKnowledgeWithOtherRowsScoresAsAFreshScorer) {
  testing::TeamFixture f(kTeam);
  Personalize(&f);
  const std::vector<double> prior(3, std::log(1.0));
  DecisionContext ctx = TeamContext(f, prior);
  ctx.knowledge = NewKnowledgeStamp();
  const auto rows = [](std::vector<int> r) {
    ScoringRows team;
    team.row_of.assign(4, -1);
    for (int b = 0; b < static_cast<int>(r.size()); ++b) team.row_of[r[b]] = b;
    team.rows = std::move(r);
    return team;
  };
  const auto score = [&](NetworkScorer* scorer, const ScoringRows& team) {
    std::vector<float> out(team.rows.size() * kNumMoves, -1.0f);
    scorer->Score(ctx, team, ScorerView{}, out.data());
    return out;
  };
  const auto fresh = [&](const ScoringRows& team) {
    NetworkScorer scorer(TestNet(ChannelFrame::kCentred, true));
    scorer.Reset(f.world.map, 4, f.world.NumTargets());
    return score(&scorer, team);
  };
  NetworkScorer kept(TestNet(ChannelFrame::kCentred, true));
  kept.Reset(f.world.map, 4, f.world.NumTargets());
  const ScoringRows all = rows({0, 1, 2, 3}), three = rows({0, 2, 3});
  const std::vector<float> first = score(&kept, all);
  EXPECT_EQ(first, fresh(all));
  EXPECT_EQ(score(&kept, three), fresh(three));
  EXPECT_EQ(score(&kept, all), first);
}

// policy.claims (route by default, so the relabelling test above holds with
// it): two targets at their priors, robot 0 beside the first, robot 1 beside
// the second, robot 2 far from both. With neighbours, robots 0 and 1 are
// shown one target each, which changes their input; robot 2 owns none,
// helps nobody (each owner holds one) and has an empty route: it sees both,
// as without claims. A robot without neighbours owns every target it can
// reach (nearest: its input is the one without claims, to the heat's
// rounding) but routes to one at a time (route: it sees one of the two).
// One policy through episodes on workspaces of other sizes decides each as
// a fresh policy does (its threads' heat grids took the first map's shape
// and the second episode aborted on a size check).
TEST(IgbNetPolicyTest, AResetOnAnotherMapDecidesAsAFreshPolicy) {
  const char* small = R"(
workspace: {size: [8, 8]}
robots: {count: 3, step: 0.5, start: [[1.25, 1.25], [6.75, 6.75], [1.25, 6.75]]}
targets: {list: [{position: [2, 2], prior_mean: [2.25, 1.75]}, {position: [6, 6], prior_mean: [6.25, 6.25]}]}
sensor: {range: 2.0}
)";
  const char* large = R"(
workspace: {size: [12, 12]}
robots: {count: 3, step: 0.5, start: [[1.25, 1.25], [10.75, 10.75], [1.25, 10.75]]}
targets: {list: [{position: [2, 2], prior_mean: [2.25, 1.75]}, {position: [10, 10], prior_mean: [10.25, 10.25]}]}
sensor: {range: 2.0}
)";
  const testing::TeamFixture a(small), b(large);
  const std::vector<double> prior(2, 0.0);
  IgbNetParams params;  // the rules' default: claims route the heat
  const auto net = TestNet(ChannelFrame::kCentred, true);
  IgbNetPolicy reused(net, params), fresh(net, params);
  Decide(&reused, a, 0, prior);
  EXPECT_EQ(Decide(&reused, b, 0, prior), Decide(&fresh, b, 0, prior));
  EXPECT_EQ(reused.logits(), fresh.logits());
}

TEST(IgbNetPolicyTest, ClaimsNarrowTheHeatToTheTargetsARobotTakes) {
  const char* yaml = R"(
workspace: {size: [8, 8]}
robots: {count: 3, step: 0.5, start: [[1.25, 1.25], [6.75, 6.75], [1.25, 6.75]]}
targets: {list: [{position: [2, 2], prior_mean: [2.25, 1.75]}, {position: [6, 6], prior_mean: [6.25, 6.25]}]}
sensor: {range: 2.0}
)";
  ASSERT_EQ(IgbNetParams().claims, TargetClaimsMode::kRoute);
  for (const TargetClaimsMode mode :
       {TargetClaimsMode::kNearest, TargetClaimsMode::kRoute}) {
    for (const bool alone : {false, true}) {
      CommParams cp;
      if (alone) {
        cp.mode = CommMode::kRange;
        cp.range = 0.5;
      }
      testing::TeamFixture f(yaml, cp);
      const std::vector<double> prior(2, 0.0);
      IgbNetParams on, off;
      on.claims = mode;
      off.claims = TargetClaimsMode::kNone;
      IgbNetPolicy with(TestNet(ChannelFrame::kCentred, true), on);
      IgbNetPolicy without(TestNet(ChannelFrame::kCentred, true), off);
      Decide(&with, f, 0, prior);
      Decide(&without, f, 0, prior);
      for (int i = 0; i < 3; ++i) {
        const auto row = [i](const std::vector<float>& l) {
          return std::vector<float>(l.begin() + i * kNumMoves,
                                    l.begin() + (i + 1) * kNumMoves);
        };
        const bool same = alone ? mode == TargetClaimsMode::kNearest : i == 2;
        if (same) {
          for (int a = 0; a < kNumMoves; ++a)
            EXPECT_NEAR(row(with.logits())[a], row(without.logits())[a], 1e-5)
                << "robot " << i;
        } else {
          EXPECT_NE(row(with.logits()), row(without.logits())) << "robot " << i;
        }
      }
    }
  }
}

TEST(IgbNetPolicyTest, TheSameGraphAtAnotherStepGivesTheSameActions) {
  for (const auto& [geodesic, hops] :
       std::vector<std::pair<bool, int>>{{false, 0}, {true, 0}, {true, 2}}) {
    testing::TeamFixture f(kTeam);
    Personalize(&f);
    const std::vector<double> prior(3, std::log(1.0));
    IgbNetPolicy policy(TestNet(ChannelFrame::kCentred, geodesic, hops));
    const std::vector<Move> a = Decide(&policy, f, 0, prior);
    const std::vector<float> la = policy.logits();
    const std::vector<Move> b = Decide(&policy, f, 317, prior);
    EXPECT_EQ(a, b);
    EXPECT_EQ(la, policy.logits());
  }
}

// A 12 x 2 m corridor: robot 0 at its west end, robot 1 beside it, one
// target believed at (10, 1.25), seen (sensor 2 m) from (8.25, 1.25) but
// from nowhere nearer the robots: the only shortest path to a point that
// sees it runs east along y = 1.25, 14 moves.
const char* kCorridor = R"(
workspace: {size: [12, 2]}
robots: {count: 2, step: 0.5, start: [[1.25, 1.25], [1.25, 0.75]]}
targets: {list: [{position: [10.5, 1.25], prior_mean: [10.0, 1.25]}]}
sensor: {range: 2.0}
)";

// Robot `r` (of 2) takes the move m its network prefers at its start, then
// the move back (one reversal), and stands where it started: with
// max_reversals 1 it is deadlocked and walks east toward the point that
// sees the target, whatever its network prefers; the other robot, which
// stayed put, takes its network's move, as without the rule. Relabelling
// the robots (their histories with them) permutes the moves: the memory is
// per robot.
TEST(IgbNetPolicyTest, DeadlockRuleWalksTowardTheNearestOpenTarget) {
  const std::vector<double> prior(1, std::log(1.0));
  int overruled = 0;  // cases where the network alone would not go east
  for (bool geodesic : {false, true}) {
    for (int r : {0, 1}) {
      testing::TeamFixture f(kCorridor);
      if (r == 1) std::swap(f.positions[0], f.positions[1]);
      const Lattice& lattice = f.world.map.lattice();
      const auto net = TestNet(ChannelFrame::kCentred, geodesic);
      IgbNetPolicy rule(net);  // max_reversals 1, the default
      IgbNetParams argmax;
      argmax.max_reversals = 0;
      argmax.no_undo = false;
      IgbNetPolicy plain(net, argmax);
      const int a = f.positions[r];
      const Move m = Decide(&plain, f, 0, prior)[r];
      const int b = lattice.Next(a, m);
      ASSERT_GE(b, 0);
      std::vector<Move> last, last_plain;
      for (int t = 0; t < 3; ++t) {
        testing::TeamFixture g(kCorridor);
        g.positions = f.positions;
        if (t == 1) g.positions[r] = b;  // a, b, a
        std::vector<Vec2> p;
        for (int idx : g.positions) p.push_back(lattice.Point(idx));
        g.comm.Update(1, p);
        last = Decide(&rule, g, t, prior, t == 0);
        last_plain = Decide(&plain, g, t, prior, t == 0);
      }
      EXPECT_EQ(last[r], Move::kRight) << "geodesic " << geodesic;
      EXPECT_EQ(last[1 - r], last_plain[1 - r]) << "geodesic " << geodesic;
      overruled += last_plain[r] != Move::kRight;
    }
  }
  EXPECT_GT(overruled, 0);
}

// Robot 0 of `yaml`, the team at `positions`, takes the move `net` alone
// prefers there and then stands where it started again (a, b, a: one
// reversal); returns what `rule` (fresh) decides at the third step, where
// its deadlock rule takes over.
std::vector<Move> Deadlocked(IgbNetPolicy* rule,
                             const std::shared_ptr<const IgbNet>& net,
                             const char* yaml,
                             const std::vector<int>& positions,
                             const std::vector<double>& prior) {
  IgbNetParams argmax;
  argmax.max_reversals = 0;
  argmax.no_undo = false;
  IgbNetPolicy plain(net, argmax);
  testing::TeamFixture f(yaml);
  f.positions = positions;
  const int b =
      f.world.map.lattice().Next(positions[0], Decide(&plain, f, 0, prior)[0]);
  EXPECT_GE(b, 0);
  std::vector<Move> last;
  for (int t = 0; t < 3; ++t) {
    testing::TeamFixture g(yaml);
    g.positions = positions;
    if (t == 1) g.positions[0] = b;
    last = Decide(rule, g, t, prior, t == 0);
  }
  return last;
}

TEST(IgbNetPolicyTest, DeadlockRuleLeavesANeighboursNearerTargetToIt) {
  // Robot 0 in the middle of the corridor, deadlocked; one target believed
  // 3.75 m east of it, one 4.75 m west (each seen from 1.75 m away: 4 moves
  // east, 6 west). Robot 1 nearer to neither: robot 0 walks east, to the
  // nearer. Robot 1 beside the east target: robot 0 leaves it and walks
  // west.
  const char* yaml = R"(
workspace: {size: [12, 2]}
robots: {count: 2, step: 0.5, start: [[6.25, 1.25], [6.25, 0.25]]}
targets: {list: [{position: [10.5, 1.25], prior_mean: [10.0, 1.25]},
                 {position: [1.0, 1.25], prior_mean: [1.5, 1.25]}]}
sensor: {range: 2.0}
)";
  const std::vector<double> prior(2, std::log(1.0));
  for (const Vec2& other : {Vec2(6.25, 0.25), Vec2(9.75, 0.75)}) {
    testing::TeamFixture f(yaml);
    f.positions[1] = f.world.map.lattice().NearestPoint(other);
    const auto net = TestNet(ChannelFrame::kCentred, true);
    IgbNetPolicy rule(net);
    const std::vector<Move> last =
        Deadlocked(&rule, net, yaml, f.positions, prior);
    EXPECT_EQ(last[0], other.x() < 9.0 ? Move::kRight : Move::kLeft)
        << "robot 1 at " << other.transpose();
  }
}

// With claims the walk heads for a target the robot owns in lattice moves.
// A wall (y 2..2.5, x from 6.5 east) parts robot 1 (9.75, 3.25) from the
// east target's aim (10, 1.25): 2.02 m away in a straight line, against
// robot 0's 3.75 m, but about 14 moves around the wall's west end against
// robot 0's 4. With claims robot 0 owns both targets and walks east, to the
// nearer; without (`none`: the straight-line rule) it leaves the east target
// to robot 1 and walks west.
TEST(IgbNetPolicyTest, DeadlockRuleWalksToTheTargetsTheRobotOwns) {
  const char* yaml = R"(
workspace: {size: [12, 4], obstacles: {boxes: [{center: [9.25, 2.25], size: [5.5, 0.5]}]}}
robots: {count: 2, step: 0.5, start: [[6.25, 1.25], [9.75, 3.25]]}
targets: {list: [{position: [10.5, 1.25], prior_mean: [10.0, 1.25]},
                 {position: [1.0, 1.25], prior_mean: [1.5, 1.25]}]}
sensor: {range: 2.0}
)";
  const std::vector<double> prior(2, std::log(1.0));
  for (const TargetClaimsMode mode :
       {TargetClaimsMode::kRoute, TargetClaimsMode::kNearest,
        TargetClaimsMode::kNone}) {
    testing::TeamFixture f(yaml);
    const auto net = TestNet(ChannelFrame::kCentred, true);
    IgbNetParams params;
    params.claims = mode;
    IgbNetPolicy rule(net, params);
    const std::vector<Move> last =
        Deadlocked(&rule, net, yaml, f.positions, prior);
    EXPECT_EQ(last[0],
              mode == TargetClaimsMode::kNone ? Move::kLeft : Move::kRight)
        << "claims " << static_cast<int>(mode);
  }
}

// The walk keeps its target: robot 0, deadlocked, leaves the east target to
// robot 1 beside it and walks west; robot 1 then runs west past it, so that
// robot 1 is nearer the west target and the east one is nobody's. Robot 0
// still walks west (choosing afresh it would turn east, as the same state
// given to a fresh policy shows); once the west target is localized it
// turns east.
TEST(IgbNetPolicyTest, DeadlockRuleKeepsItsTargetWhenClaimsChange) {
  const char* yaml = R"(
workspace: {size: [12, 2]}
robots: {count: 2, step: 0.5, start: [[6.25, 1.25], [9.75, 0.75]]}
targets: {list: [{position: [10.5, 1.25], prior_mean: [10.0, 1.25]},
                 {position: [1.0, 1.25], prior_mean: [1.5, 1.25]}]}
sensor: {range: 2.0}
)";
  const std::vector<double> prior(2, std::log(1.0));
  testing::TeamFixture g(yaml);
  const Lattice& lattice = g.world.map.lattice();
  const auto net = TestNet(ChannelFrame::kCentred, true);
  IgbNetPolicy rule(net);
  ASSERT_EQ(Deadlocked(&rule, net, yaml, g.positions, prior)[0], Move::kLeft);
  g.positions[0] = lattice.Next(g.positions[0], Move::kLeft);
  g.positions[1] = lattice.NearestPoint(Vec2(3.25, 0.25));
  EXPECT_EQ(Decide(&rule, g, 3, prior, false)[0], Move::kLeft);
  // A fresh policy, deadlocked in this state, heads east.
  IgbNetPolicy fresh(net);
  EXPECT_EQ(Deadlocked(&fresh, net, yaml, g.positions, prior)[0], Move::kRight);
  // The west target localized (in robot 0's belief): the walk turns east.
  testing::TeamFixture done(yaml);
  done.positions = g.positions;
  done.beliefs.Omega(0, 1) *= 1e6;
  done.beliefs.Xi(0, 1) *= 1e6;
  EXPECT_EQ(Decide(&rule, done, 4, prior, false)[0], Move::kRight);
}

// policy.no_undo: where the network would take robot 0 back where it came
// from, it walks toward the target (east) or stays instead, and the
// counters say so; elsewhere it takes the network's move.
TEST(IgbNetPolicyTest, NoUndoNeverTakesTheNetworksUndoMove) {
  const std::vector<double> prior(1, std::log(1.0));
  int replaced = 0;
  for (bool geodesic : {false, true}) {
    const auto net = TestNet(ChannelFrame::kCentred, geodesic);
    IgbNetParams argmax;
    argmax.max_reversals = 0;
    argmax.no_undo = false;
    IgbNetParams no_undo;
    no_undo.no_undo = true;
    for (const Vec2& at : {Vec2(3.25, 1.25), Vec2(4.75, 0.75), Vec2(2.25, 0.25),
                           Vec2(5.25, 1.75)}) {
      testing::TeamFixture f(kCorridor);
      const Lattice& lattice = f.world.map.lattice();
      f.positions[0] = lattice.NearestPoint(at);
      IgbNetPolicy plain(net, argmax);
      const Move q = Decide(&plain, f, 0, prior)[0];
      const int from = lattice.Next(f.positions[0], q);
      ASSERT_GE(from, 0);
      // Robot 0 came from `from` (by the move Opposite(q)); q undoes it.
      IgbNetPolicy policy(net, no_undo);
      testing::TeamFixture g(kCorridor);
      g.positions = f.positions;
      g.positions[0] = from;
      Decide(&policy, g, 0, prior);
      const Move m = Decide(&policy, f, 1, prior, false)[0];
      const Move came = Opposite(q);
      const long rule_moves = Counter(policy, "walk_moves");
      const long rule_stays = Counter(policy, "no_undo_stays");
      EXPECT_TRUE(m == Move::kRight || m == Move::kStay) << at.transpose();
      EXPECT_EQ(rule_moves + rule_stays, 1) << at.transpose();
      ASSERT_NE(came, Move::kStay);
      // Where the network's undo is not the walk's own move, it was
      // replaced (tests/learning/coordination_test.cc states each case by
      // hand with fixed logits).
      if (q != Move::kRight) {
        EXPECT_NE(m, q);
        ++replaced;
      }
    }
  }
  EXPECT_GT(replaced, 0);
}

// A robot whose own belief holds every target localized (a tracking
// mission after success) has nothing to measure: where the network would
// undo the last move it takes the network's best other valid move (not a
// stay: the robot keeps moving while nothing is open) and counts it.
TEST(IgbNetPolicyTest, NoUndoMovesOnWhereNothingIsOpen) {
  const std::vector<double> prior(1, std::log(1.0));
  int checked = 0;
  const auto net = TestNet(ChannelFrame::kCentred, true);
  for (const Vec2& at : {Vec2(3.25, 1.25), Vec2(4.75, 0.75), Vec2(2.25, 0.25),
                         Vec2(5.25, 1.75)}) {
    IgbNetParams argmax;
    argmax.max_reversals = 0;
    argmax.no_undo = false;
    const auto localized = [](testing::TeamFixture* f) {
      for (int i = 0; i < f->beliefs.rows(); ++i) {
        f->beliefs.Omega(i, 0) *= 1e6;
        f->beliefs.Xi(i, 0) *= 1e6;
      }
    };
    testing::TeamFixture f(kCorridor);
    localized(&f);
    const Lattice& lattice = f.world.map.lattice();
    f.positions[0] = lattice.NearestPoint(at);
    IgbNetPolicy plain(net, argmax);
    Decide(&plain, f, 0, prior);
    const std::vector<float> l(plain.logits().begin(),
                               plain.logits().begin() + kNumMoves);
    int q = -1, next = -1;  // the network's best valid move, and the next
    for (int a = 0; a < kNumMoves; ++a) {
      if (!lattice.Valid(f.positions[0], static_cast<Move>(a))) continue;
      if (q < 0 || l[a] > l[q]) {
        next = q;
        q = a;
      } else if (next < 0 || l[a] > l[next]) {
        next = a;
      }
    }
    ASSERT_GE(next, 0);
    const int from = lattice.Next(f.positions[0], static_cast<Move>(q));
    // Robot 0 came from `from`; q undoes that.
    IgbNetPolicy policy(net);
    testing::TeamFixture g(kCorridor);
    localized(&g);
    g.positions = f.positions;
    g.positions[0] = from;
    Decide(&policy, g, 0, prior);
    const Move m = Decide(&policy, f, 1, prior, false)[0];
    EXPECT_EQ(m, static_cast<Move>(next)) << at.transpose();
    EXPECT_EQ(Counter(policy, "idle_moves"), 1);
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

TEST(IgbNetPolicyTest, DeadlockRuleWalksAtMostMaxWalkMovesAndCountsThem) {
  // Robot 0 reverses once (a, b, a), walks one move east (the rule's), and
  // with max_walk 1 takes its network's move at the next point; the
  // counters say 1 rule move of 8 decisions.
  const std::vector<double> prior(1, std::log(1.0));
  testing::TeamFixture f(kCorridor);
  const Lattice& lattice = f.world.map.lattice();
  const auto net = TestNet(ChannelFrame::kCentred, true);
  IgbNetParams params;
  params.max_walk = 1;
  IgbNetPolicy rule(net, params);
  IgbNetParams argmax = params;
  argmax.max_reversals = 0;
  argmax.no_undo = false;
  IgbNetPolicy plain(net, argmax);
  const int a = f.positions[0];
  const Move m = Decide(&plain, f, 0, prior)[0];
  const int b = lattice.Next(a, m);
  ASSERT_GE(b, 0);
  const int c = lattice.Next(a, Move::kRight);
  std::vector<Move> last, last_plain;
  for (int t = 0; t < 4; ++t) {
    testing::TeamFixture g(kCorridor);
    g.positions = f.positions;
    if (t == 1) g.positions[0] = b;
    if (t == 3) g.positions[0] = c;  // where the rule's move took it
    last = Decide(&rule, g, t, prior, t == 0);
    last_plain = Decide(&plain, g, t, prior, t == 0);
    if (t == 2) EXPECT_EQ(last[0], Move::kRight);
  }
  EXPECT_EQ(last, last_plain);
  EXPECT_EQ(Counter(rule, "decisions"), 8);
  EXPECT_EQ(Counter(rule, "walk_moves"), 1);
  EXPECT_EQ(Counter(rule, "no_undo_stays"), 0);
  EXPECT_EQ(Counter(rule, "idle_moves"), 0);
  EXPECT_GE(Counter(rule, "handwritten_moves"), 1);
}

TEST(IgbNetPolicyTest, DeadlockRuleHandsBackWhereTheRobotCanMeasure) {
  // The same reversal at (8.75, 1.25), which sees the target's mean: the
  // robot takes its network's move. (Without the search memory, which would
  // move the aim once the robot measured nothing there, and without no_undo,
  // which would keep it there.)
  const std::vector<double> prior(1, std::log(1.0));
  testing::TeamFixture f(kCorridor);
  const Lattice& lattice = f.world.map.lattice();
  f.positions[0] = lattice.NearestPoint(Vec2(8.75, 1.25));
  const auto net = TestNet(ChannelFrame::kCentred, true);
  IgbNetParams params;
  params.search = false;
  params.no_undo = false;
  IgbNetPolicy rule(net, params);
  IgbNetParams argmax = params;
  argmax.max_reversals = 0;
  argmax.no_undo = false;
  IgbNetPolicy plain(net, argmax);
  const int a = f.positions[0];
  const Move m = Decide(&plain, f, 0, prior)[0];
  std::vector<Move> last, last_plain;
  for (int t = 0; t < 3; ++t) {
    testing::TeamFixture g(kCorridor);
    g.positions = f.positions;
    if (t == 1) g.positions[0] = lattice.Next(a, m);
    last = Decide(&rule, g, t, prior, t == 0);
    last_plain = Decide(&plain, g, t, prior, t == 0);
  }
  EXPECT_EQ(last, last_plain);
}

TEST(IgbNetPolicyTest, SearchMemoryIsPerRobot) {
  // In the corridor, one robot stands where it sees the target's mean, the
  // other far from it; their beliefs stay as they are for three decisions
  // (nothing measured). Without sharing, the first remembers its own point,
  // the second nothing; swapping their labels swaps what they remember.
  const std::vector<double> prior(1, std::log(1.0));
  std::vector<std::vector<int>> missed[2];
  for (int swap = 0; swap < 2; ++swap) {
    testing::TeamFixture f(kCorridor);
    const Lattice& lattice = f.world.map.lattice();
    f.positions[1 - swap] = lattice.NearestPoint(Vec2(8.75, 1.25));
    std::vector<Vec2> p;
    for (int idx : f.positions) p.push_back(lattice.Point(idx));
    f.comm.Update(1, p);
    IgbNetParams own;
    own.share_search = false;
    IgbNetPolicy policy(TestNet(ChannelFrame::kCentred, true), own);
    for (int t = 0; t < 3; ++t) Decide(&policy, f, t, prior, t == 0);
    for (int i = 0; i < 2; ++i)
      missed[swap].push_back(policy.search().Missed(i, 0));
    EXPECT_EQ(missed[swap][1 - swap],
              std::vector<int>{lattice.NearestPoint(Vec2(8.75, 1.25))});
    EXPECT_TRUE(missed[swap][swap].empty());
  }
  EXPECT_EQ(missed[1][0], missed[0][1]);
  EXPECT_EQ(missed[1][1], missed[0][0]);
}

TEST(IgbNetPolicyTest, NeighboursShareWhatTheyMissed) {
  // The same, sharing (the default): the far robot, a neighbour in the full
  // graph, takes in the other's missed point and aims where it does not
  // see; in a graph without that edge it does not.
  const std::vector<double> prior(1, std::log(1.0));
  for (bool connected : {true, false}) {
    CommParams cp;
    if (!connected) {
      cp.mode = CommMode::kRange;
      cp.range = 2.0;  // the robots stand 7.5 m apart
    }
    testing::TeamFixture f(kCorridor, cp);
    const Lattice& lattice = f.world.map.lattice();
    const int seer = lattice.NearestPoint(Vec2(8.75, 1.25));
    f.positions[1] = seer;
    std::vector<Vec2> p;
    for (int idx : f.positions) p.push_back(lattice.Point(idx));
    f.comm.Update(1, p);
    IgbNetPolicy policy(TestNet(ChannelFrame::kCentred, true));
    for (int t = 0; t < 3; ++t) Decide(&policy, f, t, prior, t == 0);
    EXPECT_EQ(policy.search().Missed(1, 0), std::vector<int>{seer});
    if (connected) {
      EXPECT_EQ(policy.search().Missed(0, 0), std::vector<int>{seer});
      EXPECT_EQ(PredictedPrecision(f.world.map, f.sensor, lattice.Point(seer),
                                   policy.search().Aim(0, 0)),
                0.0);
    } else {
      EXPECT_TRUE(policy.search().Missed(0, 0).empty());
    }
  }
}

TEST(IgbNetPolicyTest, TakesOnlyValidMoves) {
  testing::TeamFixture f(kTeam);
  const std::vector<double> prior(3, 0.0);
  IgbNetPolicy policy(TestNet(ChannelFrame::kCentred));
  // A robot in the corner: left and down are not valid.
  f.positions[0] = f.world.map.lattice().NearestPoint({0.25, 0.25});
  for (int seed = 0; seed < 5; ++seed) {
    IgbNetPolicy p(std::make_shared<const IgbNet>(SmallConfig(), seed));
    const std::vector<Move> moves = Decide(&p, f, 0, prior);
    for (int i = 0; i < 4; ++i)
      EXPECT_TRUE(f.world.map.lattice().Valid(f.positions[i], moves[i]));
  }
}

// A build's default model is its source tree's, whatever the working folder
// holds (a script run from a folder with a models/igbnet.pt of its own
// decided with that file before, and nothing recorded it).
TEST(IgbNetTest, TheDefaultModelIsTheSourceTreesWhereverTheProgramRuns) {
  const std::string dir = testing::MakeTempDir("aia_cwd_");
  fs::create_directories(dir + "/models");
  fs::copy_file(testing::SourcePath("models/igbnet_10x10.pt"),
                dir + "/models/igbnet.pt");
  fs::copy_file(testing::SourcePath("models/igbnet_10x10.pt"),
                dir + "/models/igbnet_learned.pt");
  const fs::path before = fs::current_path();
  fs::current_path(dir);
  // (Resolved here: a relative path names the working folder's file.)
  const fs::path rules =
      fs::weakly_canonical(DefaultModelPath(Coordination::kRules));
  const fs::path none =
      fs::weakly_canonical(DefaultModelPath(Coordination::kNone));
  fs::current_path(before);
  EXPECT_EQ(rules,
            fs::weakly_canonical(testing::SourcePath("models/igbnet.pt")));
  EXPECT_EQ(none, fs::weakly_canonical(
                      testing::SourcePath("models/igbnet_learned.pt")));
  fs::remove_all(dir);
}

// build/aia's main sets libtorch's OpenMP spin for the whole process before
// any thread (so that loading the plugin needs no setenv, which races with
// a getenv on another thread), unless the caller chose a wait of its own.
TEST(OpenMpSpinTest, ShortUnlessTheCallerChoseAWait) {
  const auto value = [] {
    const char* v = ::getenv("GOMP_SPINCOUNT");
    return v ? std::string(v) : std::string("(unset)");
  };
  const char* policy = ::getenv("OMP_WAIT_POLICY");
  const char* spin = ::getenv("GOMP_SPINCOUNT");
  const std::string had_policy = policy ? policy : "",
                    had_spin = spin ? spin : "";
  ::unsetenv("OMP_WAIT_POLICY");
  ::unsetenv("GOMP_SPINCOUNT");
  PreferShortOpenMpSpin();
  EXPECT_EQ(value(), "1000");
  ::setenv("GOMP_SPINCOUNT", "77", 1);
  PreferShortOpenMpSpin();
  EXPECT_EQ(value(), "77");
  ::unsetenv("GOMP_SPINCOUNT");
  ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
  PreferShortOpenMpSpin();
  EXPECT_EQ(value(), "(unset)");
  ::unsetenv("OMP_WAIT_POLICY");
  if (policy) ::setenv("OMP_WAIT_POLICY", had_policy.c_str(), 1);
  if (spin) ::setenv("GOMP_SPINCOUNT", had_spin.c_str(), 1);
}

}  // namespace
}  // namespace aia
