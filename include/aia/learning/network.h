// I-GBNet's network (docs/learning.md, Network): a conv stem, 3 residual
// blocks (Conv3x3-BN-ReLU-Conv3x3-BN, skip, ReLU), adaptive average pooling
// to a fixed pool x pool grid (any workspace size maps to the same size) and
// an MLP to 4 logits, one per move (core/types.h order: left, right, up,
// down). Optionally (message_hops K > 0) the robots exchange their hidden
// features over this step's communication graph before the last layer: a
// K-tap graph filter h_i = relu(z_i + sum_k M_k (S^k z)_i), S the mean over a
// robot's neighbours, so the network stays equivariant to relabelling the
// robots and has no notion of time. libtorch stays behind this header: it
// lives in a plugin, libaia_torch.so (src/learning/torch/), that the first
// network made or loaded brings in (src/learning/torch_backend.cc), so that a
// process which never uses one starts without it.
#ifndef AIA_LEARNING_NETWORK_H_
#define AIA_LEARNING_NETWORK_H_

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "aia/core/hash.h"
#include "aia/core/thread_pool.h"
#include "aia/learning/channels.h"

namespace aia {

inline constexpr int kMaxMessageHops = 8;

struct NetworkConfig {
  ChannelParams channels;
  int width = 32;       // feature channels of the stem and the blocks
  int stem_stride = 2;  // the stem's stride (docs/learning.md, Network)
  int pool = 5;         // P: adaptive pooling to P x P
  int hidden = 128;     // the MLP's hidden units
  // C: the C x C cells of the blocks' output around the robot's own cell,
  // read by the MLP beside the pooled grid (odd; 0: none; the centred frame
  // only): the detail next to the robot that the pooling averages away.
  int centre = 0;
  // K: hops of learned message passing over the communication graph (0:
  // none, each robot alone; the paper's network).
  int message_hops = 0;

  // Declared once, for the model file's metadata and `aia train`'s flags:
  // the channels' keys sit beside the network's (the metadata is flat).
  template <typename Archive>
  void Serialize(Archive* a) {
    channels.Serialize(a);
    a->Visit(AIA_FIELD(width)
                 .In(Between(1, 512))
                 .Doc("feature channels of the stem and the blocks"));
    a->Visit(AIA_FIELD(stem_stride)
                 .In(Between(1, 4))
                 .Doc("stride of the stem (docs/learning.md, Network)"));
    a->Visit(
        AIA_FIELD(pool).In(Between(1, 32)).Doc("P: adaptive pooling to P x P"));
    a->Visit(
        AIA_FIELD(hidden).In(Between(1, 4096)).Doc("the MLP's hidden units"));
    a->Visit(AIA_FIELD(centre)
                 .In(Between(0, 31))
                 .Doc("C: the C x C cells of the blocks' output around the "
                      "robot, read by the MLP beside the pooled grid (odd; 0: "
                      "none; centred frame)"));
    a->Visit(AIA_FIELD(message_hops)
                 .In(Between(0, kMaxMessageHops))
                 .Doc("K: hops of learned message passing over the "
                      "communication graph (0: none)"));
  }

  // The model file's metadata (JSON), and back; FromJson throws
  // std::runtime_error on anything missing or out of range (the ranges
  // above).
  std::string ToJson() const;
  static NetworkConfig FromJson(const std::string& json);

  // The blocks' output is FeatureSide() x FeatureSide() cells (the stem's
  // padded 3 x 3 convolution of stride stem_stride over the window); the
  // centre's first row and column (the robot's cell minus centre / 2).
  int FeatureSide() const;
  int CentreStart() const;
  // Why `centre` cannot be read with these channels (even, the global
  // frame, or beyond the blocks' output); empty when it can.
  std::string CentreProblem() const;
};

// A team's communication graph for message passing: the neighbours of row b
// of a batch are rows neighbours[offsets[b] .. offsets[b + 1]); offsets has
// batch + 1 entries. Self-loops and rows outside the batch are not allowed.
struct TeamGraph {
  std::vector<int> offsets{0};
  std::vector<int> neighbours;
  int rows() const { return static_cast<int>(offsets.size()) - 1; }
};

// The arithmetic of inference's convolutions (policy.precision): float32,
// as the network was trained; or bfloat16 (8 bits of mantissa, products
// summed in float32), which oneDNN runs on AMX or AVX-512 BF16 about three
// times as fast; auto, bfloat16 for a team of kBFloat16Team robots or more
// on a CPU that multiplies bfloat16 natively, float32 otherwise (so that
// teams of the training data's sizes run as trained). The stem and the
// residual blocks only; pooling and the MLP stay float32.
enum class Precision { kAuto, kFloat32, kBFloat16 };
constexpr std::array<EnumName<Precision>, 3> EnumNames(Precision) {
  return {{{Precision::kAuto, "auto"},
           {Precision::kFloat32, "float32"},
           {Precision::kBFloat16, "bfloat16"}}};
}
inline constexpr int kBFloat16Team = 100;

// Whether this CPU multiplies bfloat16 natively (AMX-BF16 or AVX-512 BF16,
// with the operating system's AVX-512 state on) and libtorch has oneDNN;
// loads libtorch.
bool NativeBFloat16();
// Why `precision` cannot run here ("" when it can): bfloat16 on a CPU
// without NativeBFloat16(), where oneDNN would emulate it slower than
// float32, or not at all.
std::string PrecisionProblem(Precision precision);
// Whether `precision` runs in bfloat16 for a team of `robots` (auto as
// above); a PrecisionProblem is a std::runtime_error.
bool UsesBFloat16(Precision precision, int robots);

class TorchNet;       // src/learning/torch/torch_net.h
struct TorchBackend;  // src/learning/torch_backend.h

class IgbNet {
 public:
  // A freshly initialized network (libtorch's default initialization,
  // seeded). This and Load bring libtorch in; a missing or broken plugin is
  // a std::runtime_error.
  IgbNet(const NetworkConfig& config, std::uint64_t seed);
  ~IgbNet();
  IgbNet(const IgbNet&) = delete;
  IgbNet& operator=(const IgbNet&) = delete;

  // A saved model. A missing file, one that is not a model, or one whose
  // tensors do not match its own metadata is an InputError at
  // (`error_file`, `error_line`, `key`).
  static std::unique_ptr<IgbNet> Load(const std::string& path,
                                      const std::string& error_file,
                                      int error_line, const std::string& key);
  // Writes the model (weights, batch-norm statistics and metadata) to a
  // temporary file and renames it over `path`.
  void Save(const std::string& path) const;

  const NetworkConfig& config() const;
  // The file a loaded model was read from: its absolute path and the
  // SHA-256 of the bytes read (empty for a network made in memory).
  const FileIdentity& file() const;
  // Inference (evaluation mode, no gradients; safe from several threads):
  // `images` holds `batch` images of kNumChannels x height x width floats;
  // writes batch x 4 logits; `bfloat16` as Precision above (only where
  // NativeBFloat16()).
  // With message_hops > 0 every robot of the batch counts as alone (no
  // neighbours); the team's call is Embed and Head below.
  void Forward(const float* images, int batch, int height, int width,
               float* logits, bool bfloat16 = false) const;
  // The two halves of Forward for message passing: Embed writes batch x
  // hidden features (the MLP's hidden layer); Head takes the whole team's
  // features and its graph (graph.rows() robots) and writes their logits.
  // Head runs on the calling thread (its result does not depend on
  // PolicyThreads()), through the same layers as training.
  void Embed(const float* images, int batch, int height, int width,
             float* features, bool bfloat16 = false) const;
  void Head(const float* features, const TeamGraph& graph, float* logits) const;
  // Number of trainable parameters.
  std::int64_t NumParameters() const;

 private:
  IgbNet(const TorchBackend* backend, TorchNet* net);
  const TorchBackend* backend_;  // the plugin's table
  TorchNet* net_;                // owned; made and destroyed by the plugin
};

// Sets libtorch's intra-op threads (0: leave its default); both load
// libtorch.
void SetInferenceThreads(int threads);
int InferenceThreads();

// For a program's main, before it starts any thread: libtorch's OpenMP
// threads spin 1 000 turns after their work (not GNU OpenMP's 300 000, which
// held a core the policy and physics need) unless OMP_WAIT_POLICY or
// GOMP_SPINCOUNT is set, for the whole process and its children. Without
// it the setting is made and taken back as the plugin loads.
void PreferShortOpenMpSpin();

// Threads of the learned policy's rendering and inference (workers of
// ParallelFor; 1 until set; 0 leaves it). Each runs libtorch single-threaded.
void SetPolicyThreads(int threads);
int PolicyThreads();

namespace internal {
// While one lives, inference in this process runs every convolution on
// plain tensors (ATen picks oneDNN's kernels for a batch of two or more
// and reorders the activations around each): the reference its tests
// compare the oneDNN tensors' path with, bit for bit.
class PlainConvolutions {
 public:
  PlainConvolutions();
  ~PlainConvolutions();
  PlainConvolutions(const PlainConvolutions&) = delete;
  PlainConvolutions& operator=(const PlainConvolutions&) = delete;

 private:
  bool was_;
};
}  // namespace internal

// Runs f(begin, end, worker) over [0, n) in chunks of `grain` on
// PolicyThreads() threads, worker in [0, PolicyThreads()); libtorch runs
// single-threaded in each (nested OpenMP teams spin against each other on
// two cores). Each index is visited once; what f writes per index must not
// depend on the split.
void ParallelFor(int n, int grain, const std::function<void(int, int, int)>& f);

// Before the network's `chunks` run through ParallelFor: libtorch's threads
// on the calling thread, all the policy's while one chunk runs there alone,
// one while the pool's threads share the chunks (as each of them runs one).
// Only where PolicyThreads() > 1 (a command gave the policy the machine);
// changed only when the choice changes (each change makes libtorch a new
// team of threads).
void PrepareCallerTorchThreads(int chunks);
// ParallelFor in chunks of 16 as a RangeRunner (core/thread_pool.h), for
// the parts of the learned policy that split the robots, and the episode's
// fusion of a large team (estimation/team_estimate.h).
const RangeRunner& PolicyRunner();

}  // namespace aia

#endif  // AIA_LEARNING_NETWORK_H_
