// Loads the libtorch plugin (src/learning/torch_backend.h) and forwards
// IgbNet, Train, Validate, MeasureNetworkSpeed and the inference threads to
// it.
#include "torch_backend.h"

#include <stdlib.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "aia/core/check.h"

#ifndef AIA_TORCH_PLUGIN
#error "AIA_TORCH_PLUGIN: the plugin's path, set by CMakeLists.txt"
#endif

namespace aia {
namespace {

std::atomic<const TorchBackend*> loaded{nullptr};

// Neither GNU OpenMP setting of its wait is the caller's own.
bool WaitUnset() {
  return ::getenv("OMP_WAIT_POLICY") == nullptr &&
         ::getenv("GOMP_SPINCOUNT") == nullptr;
}

// libtorch's OpenMP threads spin for a while after each parallel region
// (GNU OpenMP: 300 000 turns by default), holding a core the policy's own
// threads and the physics need: on a busy machine a 10 x 10 step's policy
// took 19 to 194 ms and a 200-robot async step's 145 to 484 (3.9 and 4.3
// ms, 85 to 123 when idle). After 1 000 turns they sleep: 12.6 to 13.2 and
// 154 to 156 ms busy, and no slower idle (3.4 to 4.0 ms against 3.5 to
// 3.9). (Waiting passively from the start, as OMP_WAIT_POLICY=PASSIVE,
// cost 1 ms of the idle 10 x 10 step.) GNU OpenMP reads the setting once,
// as the plugin loads it.
constexpr char kShortSpin[] = "1000";

const TorchBackend* LoadBackend() {
  // Set for the load only where no program's main set it before its
  // threads (PreferShortOpenMpSpin: build/aia) and the caller set neither:
  // an OpenMP runtime loaded later, a Python program's PyTorch, keeps its
  // own default. (setenv races with a getenv on another thread: a native
  // thread of a Python program at this moment, not build/aia's.)
  struct ShortSpinWhileLoading {
    const bool set = WaitUnset();
    ShortSpinWhileLoading() {
      if (set) ::setenv("GOMP_SPINCOUNT", kShortSpin, /*overwrite=*/0);
    }
    ~ShortSpinWhileLoading() {
      if (set) ::unsetenv("GOMP_SPINCOUNT");
    }
  };
  const TorchBackend* table;
  {
    const ShortSpinWhileLoading short_spin;
    table = static_cast<const TorchBackend*>(LoadPluginTable(
        AIA_TORCH_PLUGIN, kTorchBackendSymbol,
        PluginHeader{kTorchBackendVersion, sizeof(TorchBackend)},
        "libtorch's plugin: the learned policy and training need it"));
  }
  loaded = table;
  return table;
}

}  // namespace

const TorchBackend& Torch() {
  static const TorchBackend* const table = LoadBackend();
  return *table;
}

const TorchBackend* TorchIfLoaded() { return loaded.load(); }

void PreferShortOpenMpSpin() {
  if (WaitUnset()) ::setenv("GOMP_SPINCOUNT", kShortSpin, /*overwrite=*/0);
}

IgbNet::IgbNet(const TorchBackend* backend, TorchNet* net)
    : backend_(backend), net_(net) {
  AIA_CHECK(backend_ && net_);
}

IgbNet::IgbNet(const NetworkConfig& config, std::uint64_t seed)
    : IgbNet(&Torch(), Torch().create(config, seed)) {}

IgbNet::~IgbNet() { backend_->destroy(net_); }

std::unique_ptr<IgbNet> IgbNet::Load(const std::string& path,
                                     const std::string& error_file,
                                     int error_line, const std::string& key) {
  const TorchBackend& torch = Torch();
  return std::unique_ptr<IgbNet>(
      new IgbNet(&torch, torch.load(path, error_file, error_line, key)));
}

void IgbNet::Save(const std::string& path) const {
  backend_->save(*net_, path);
}

const NetworkConfig& IgbNet::config() const { return backend_->config(*net_); }

const FileIdentity& IgbNet::file() const { return backend_->file(*net_); }

void IgbNet::Forward(const float* images, int batch, int height, int width,
                     float* logits, bool bfloat16) const {
  backend_->infer(*net_, images, batch, height, width, false, bfloat16, logits);
}

void IgbNet::Embed(const float* images, int batch, int height, int width,
                   float* features, bool bfloat16) const {
  backend_->infer(*net_, images, batch, height, width, true, bfloat16,
                  features);
}

bool NativeBFloat16() { return Torch().native_bfloat16(); }

std::string PrecisionProblem(Precision precision) {
  if (precision != Precision::kBFloat16 || NativeBFloat16()) return "";
  return "bfloat16: this CPU has no native bfloat16 (AMX-BF16 or AVX-512 "
         "BF16), or libtorch has no oneDNN; use float32 or auto";
}

bool UsesBFloat16(Precision precision, int robots) {
  if (const std::string why = PrecisionProblem(precision); !why.empty())
    throw std::runtime_error(why);
  return precision == Precision::kBFloat16 ||
         (precision == Precision::kAuto && robots >= kBFloat16Team &&
          NativeBFloat16());
}

void IgbNet::Head(const float* features, const TeamGraph& graph,
                  float* logits) const {
  backend_->head(*net_, features, graph, logits);
}

std::int64_t IgbNet::NumParameters() const {
  return backend_->num_parameters(*net_);
}

void SetInferenceThreads(int threads) {
  if (threads > 0) Torch().set_threads(threads);
}

int InferenceThreads() { return Torch().threads(); }

namespace internal {
PlainConvolutions::PlainConvolutions()
    : was_(Torch().set_onednn_layout(false)) {}
PlainConvolutions::~PlainConvolutions() { Torch().set_onednn_layout(was_); }
}  // namespace internal

std::vector<EpochLog> Train(const TrainOptions& options) {
  return Torch().train(options);
}

ValidationResult Validate(const std::string& model,
                          const std::vector<std::string>& data,
                          double val_share, std::uint64_t seed,
                          bool valid_moves) {
  return Torch().validate(model, data, val_share, seed, valid_moves);
}

double MeasureNetworkSpeed(const NetworkConfig& config, int height, int width,
                           int batch, bool train, int iterations, int repeats,
                           bool bf16) {
  return Torch().network_speed(config, height, width, batch, train, iterations,
                               repeats, bf16);
}

}  // namespace aia
