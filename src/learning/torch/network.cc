#include <unistd.h>

#if defined(__x86_64__)
#include <cpuid.h>
#endif

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <new>
#include <stdexcept>
#include <vector>

#include "aia/core/check.h"
#include "aia/core/error.h"
#include "aia/core/io.h"
#include "archive.h"
#include "torch_net.h"

namespace aia {
namespace {

// The metadata's JSON (its format and versions) is NetworkConfig's
// (src/learning/network.cc).
constexpr const char* kMetaKey = "aia_meta";

}  // namespace

ResidualBlockImpl::ResidualBlockImpl(int width) {
  namespace nn = torch::nn;
  const auto conv = [width] {
    return nn::Conv2d(
        nn::Conv2dOptions(width, width, 3).padding(1).bias(false));
  };
  conv1 = register_module("conv1", conv());
  bn1 = register_module("bn1", nn::BatchNorm2d(width));
  conv2 = register_module("conv2", conv());
  bn2 = register_module("bn2", nn::BatchNorm2d(width));
}

torch::Tensor ResidualBlockImpl::forward(const torch::Tensor& x) {
  torch::Tensor y = torch::relu(bn1(conv1(x)));
  y = bn2(conv2(y));
  return torch::relu(y + x);
}

IgbNetModuleImpl::IgbNetModuleImpl(const NetworkConfig& c) {
  namespace nn = torch::nn;
  stem = register_module(
      "stem",
      nn::Conv2d(nn::Conv2dOptions(c.channels.num_channels(), c.width, 3)
                     .stride(c.stem_stride)
                     .padding(1)
                     .bias(false)));
  stem_bn = register_module("stem_bn", nn::BatchNorm2d(c.width));
  blocks = register_module("blocks", nn::ModuleList());
  for (int i = 0; i < 3; ++i) blocks->push_back(ResidualBlock(c.width));
  pool = register_module(
      "pool", nn::AdaptiveAvgPool2d(nn::AdaptiveAvgPool2dOptions(c.pool)));
  centre = c.centre;
  centre_start = c.CentreStart();
  fc1 = register_module(
      "fc1",
      nn::Linear(c.width * (c.pool * c.pool + c.centre * c.centre), c.hidden));
  fc2 = register_module("fc2", nn::Linear(c.hidden, kNumMoves));
  for (int k = 1; k <= c.message_hops; ++k) {
    messages.push_back(register_module(
        "message" + std::to_string(k),
        nn::Linear(nn::LinearOptions(c.hidden, c.hidden).bias(false))));
  }
}

torch::Tensor IgbNetModuleImpl::embed(const torch::Tensor& input) {
  torch::Tensor x = torch::relu(stem_bn(stem(input)));
  for (const auto& block : *blocks) x = block->as<ResidualBlock>()->forward(x);
  torch::Tensor features = pool(x).flatten(1);
  if (centre > 0) {
    features = torch::cat({features, x.narrow(2, centre_start, centre)
                                         .narrow(3, centre_start, centre)
                                         .flatten(1)},
                          1);
  }
  return torch::relu(fc1(features));
}

torch::Tensor IgbNetModuleImpl::head(const torch::Tensor& z,
                                     const GraphTensors* graph) {
  if (messages.empty() || !graph) return fc2(z);
  torch::Tensor h = z, hop = z;
  for (torch::nn::Linear& m : messages) {
    hop = torch::zeros_like(hop).index_add(0, graph->dst,
                                           hop.index_select(0, graph->src)) *
          graph->inv_degree.unsqueeze(1);
    h = h + m(hop);
  }
  return fc2(torch::relu(h));
}

torch::Tensor IgbNetModuleImpl::forward(const torch::Tensor& input) {
  return head(embed(input), nullptr);
}

torch::Tensor IgbNetModuleImpl::forward(const torch::Tensor& input,
                                        const GraphTensors& graph) {
  return head(embed(input), &graph);
}

GraphTensors ToTensors(const TeamGraph& graph) {
  const int n = graph.rows();
  AIA_CHECK(n >= 0 && graph.offsets.front() == 0 &&
            graph.offsets.back() == static_cast<int>(graph.neighbours.size()));
  std::vector<int64_t> src, dst;
  std::vector<float> inv(n, 0.0f);
  src.reserve(graph.neighbours.size());
  dst.reserve(graph.neighbours.size());
  for (int b = 0; b < n; ++b) {
    const int d = graph.offsets[b + 1] - graph.offsets[b];
    AIA_CHECK(d >= 0);
    if (d > 0) inv[b] = 1.0f / static_cast<float>(d);
    for (int e = graph.offsets[b]; e < graph.offsets[b + 1]; ++e) {
      const int j = graph.neighbours[e];
      AIA_CHECK_MSG(j >= 0 && j < n && j != b, "a neighbour outside the batch");
      src.push_back(j);
      dst.push_back(b);
    }
  }
  const auto ints = [](const std::vector<int64_t>& v) {
    return torch::tensor(torch::ArrayRef<int64_t>(v), torch::kInt64);
  };
  return {ints(src), ints(dst),
          torch::tensor(torch::ArrayRef<float>(inv), torch::kFloat32)};
}

TorchNet::TorchNet() : impl_(std::make_unique<Impl>()) {}

TorchNet::Impl& TorchNet::impl() {
  std::lock_guard<std::mutex> lock(impl_->folded_mutex);
  impl_->folded.reset();
  return *impl_;
}

namespace {

std::atomic<bool> onednn_layout{true};

std::pair<torch::Tensor, torch::Tensor> FoldInto(
    const torch::nn::Conv2d& conv, const torch::nn::BatchNorm2d& bn) {
  const torch::Tensor g =
      bn->weight / torch::sqrt(bn->running_var + bn->options.eps());
  return {(conv->weight * g.view({-1, 1, 1, 1})).contiguous(),
          (bn->bias - bn->running_mean * g).contiguous()};
}

}  // namespace

void Transplant(IgbNetModule& from, IgbNetModule& to) {
  torch::NoGradGuard no_grad;
  auto params = to->named_parameters();
  auto buffers = to->named_buffers();
  for (const auto& p : from->named_parameters()) {
    torch::Tensor* t = params.find(p.key());
    if (!t) continue;
    if (t->sizes() == p.value().sizes()) {
      t->copy_(p.value());
    } else {  // the stem [width, channels, 3, 3] or fc1 [hidden, inputs]
      AIA_CHECK(t->dim() == p.value().dim() && t->dim() >= 2);
      const int64_t common = std::min(t->size(1), p.value().size(1));
      t->zero_();
      t->narrow(1, 0, common).copy_(p.value().narrow(1, 0, common));
    }
  }
  for (std::size_t k = from->messages.size(); k < to->messages.size(); ++k)
    to->messages[k]->weight.zero_();
  for (const auto& b : from->named_buffers())
    if (torch::Tensor* t = buffers.find(b.key())) t->copy_(b.value());
}

bool SetOneDnnLayout(bool on) { return onednn_layout.exchange(on); }

namespace {

// Whether libtorch runs convolutions on oneDNN here.
bool OneDnnOn() {
  return at::hasMKLDNN() && at::globalContext().userEnabledMkldnn();
}

}  // namespace

bool NativeBFloat16Kernels() {
  static const bool native = [] {
    if (!OneDnnOn()) return false;
    // oneDNN's own cap on the instructions it uses (its documentation's
    // ONEDNN_MAX_CPU_ISA, or the older DNNL_): below AVX512_CORE_BF16 it
    // emulates bfloat16.
    for (const char* name : {"ONEDNN_MAX_CPU_ISA", "DNNL_MAX_CPU_ISA"}) {
      const char* cap = std::getenv(name);
      if (cap == nullptr || *cap == '\0') continue;
      std::string isa(cap);
      for (char& ch : isa) ch = static_cast<char>(std::toupper(ch));
      if (isa != "ALL" && isa.find("BF16") == std::string::npos &&
          isa.find("AMX") == std::string::npos &&
          isa.find("FP16") == std::string::npos)
        return false;
      break;
    }
#if defined(__x86_64__)
    unsigned a = 0, b = 0, c = 0, d = 0;
    // OSXSAVE, then XCR0: the operating system saves the SSE, AVX and
    // AVX-512 (opmask, ZMM_Hi256, Hi16_ZMM) state.
    if (!__get_cpuid(1, &a, &b, &c, &d) || !(c & (1u << 27))) return false;
    unsigned lo = 0, hi = 0;
    __asm__("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
    if ((lo & 0xE6u) != 0xE6u || __get_cpuid_max(0, nullptr) < 7) return false;
    __cpuid_count(7, 0, a, b, c, d);
    const bool avx512f = (b & (1u << 16)) != 0;
    const bool amx_bf16 = (d & (1u << 22)) != 0;
    __cpuid_count(7, 1, a, b, c, d);
    const bool avx512_bf16 = (a & (1u << 5)) != 0;
    return avx512f && (avx512_bf16 || amx_bf16);
#else
    return false;
#endif
  }();
  return native;
}

namespace {

// f's stem and blocks in oneDNN's layout and `type`.
OneDnnLayers ForOneDnn(const FoldedNet& f, const NetworkConfig& config,
                       torch::ScalarType type) {
  const auto reorder = [type](const torch::Tensor& w, int64_t stride) {
    return at::mkldnn_reorder_conv2d_weight(w.to(type).to_mkldnn(), {1, 1},
                                            {stride, stride}, {1, 1}, 1);
  };
  OneDnnLayers l;
  l.stem_w = reorder(f.stem_w, config.stem_stride);
  l.stem_b = f.stem_b.to(type);
  for (const auto& b : f.blocks)
    l.blocks.push_back(
        {reorder(b[0], 1), b[1].to(type), reorder(b[2], 1), b[3].to(type)});
  return l;
}

// The stem and the blocks on oneDNN's tensors: `input` in the layers' type,
// the features back as plain float32.
torch::Tensor RunOneDnn(const OneDnnLayers& l, const torch::Tensor& input,
                        int64_t stem_stride) {
  const auto conv = [](const torch::Tensor& in, const torch::Tensor& w,
                       const torch::Tensor& b, int64_t stride) {
    return at::mkldnn_convolution(in, w, b, {1, 1}, {stride, stride}, {1, 1},
                                  1);
  };
  torch::Tensor h =
      torch::relu(conv(input.to(l.stem_b.scalar_type()).to_mkldnn(), l.stem_w,
                       l.stem_b, stem_stride));
  for (const auto& b : l.blocks) {
    torch::Tensor y = torch::relu(conv(h, b[0], b[1], 1));
    y = conv(y, b[2], b[3], 1);
    h = torch::relu(y + h);
  }
  return h.to_dense().to(torch::kFloat32);
}

}  // namespace

FoldedNet Fold(IgbNetModule& module, const NetworkConfig& config) {
  torch::NoGradGuard no_grad;
  FoldedNet f;
  std::tie(f.stem_w, f.stem_b) = FoldInto(module->stem, module->stem_bn);
  for (const auto& b : *module->blocks) {
    const auto* block = b->as<ResidualBlock>();
    const auto [w1, b1] = FoldInto(block->conv1, block->bn1);
    const auto [w2, b2] = FoldInto(block->conv2, block->bn2);
    f.blocks.push_back({w1, b1, w2, b2});
  }
  // fc1 as a convolution whose kernel covers the pooled grid: oneDNN's
  // kernels instead of the reference BLAS that Linear's matrix product
  // calls (the pooled C x P x P features flatten in the kernel's order),
  // and one over the centre.
  const torch::Tensor w = module->fc1->weight.detach();
  const int64_t pooled = int64_t{config.width} * config.pool * config.pool;
  f.fc1_w = w.narrow(1, 0, pooled)
                .reshape({w.size(0), config.width, config.pool, config.pool})
                .contiguous();
  if (config.centre > 0) {
    f.fc1_centre_w =
        w.narrow(1, pooled, w.size(1) - pooled)
            .reshape({w.size(0), config.width, config.centre, config.centre})
            .contiguous();
  }
  f.fc1_b = module->fc1->bias.detach();
  f.onednn = OneDnnOn();
  if (f.onednn) f.f32 = ForOneDnn(f, config, torch::kFloat32);
  f.bf16 = f.onednn && NativeBFloat16Kernels();
  if (f.bf16) f.bf16_layers = ForOneDnn(f, config, torch::kBFloat16);
  return f;
}

torch::Tensor FoldedEmbed(const FoldedNet& f, IgbNetModule& module,
                          const NetworkConfig& config,
                          const torch::Tensor& input, bool bf16) {
  torch::Tensor x;
  if (bf16) {
    // oneDNN's bfloat16 kernels (AMX where there is one), any batch.
    AIA_CHECK_MSG(f.bf16, "bfloat16 inference without native bfloat16");
    x = RunOneDnn(f.bf16_layers, input, config.stem_stride);
  } else if (f.onednn && input.size(0) >= 2 && onednn_layout.load()) {
    // FoldedNet: the same numbers.
    x = RunOneDnn(f.f32, input, config.stem_stride);
  } else {
    x = torch::relu(
        torch::conv2d(input, f.stem_w, f.stem_b, config.stem_stride, 1));
    for (const auto& b : f.blocks) {
      torch::Tensor y = torch::relu(torch::conv2d(x, b[0], b[1], 1, 1));
      y = torch::conv2d(y, b[2], b[3], 1, 1);
      x = torch::relu(y + x);
    }
  }
  torch::Tensor z = torch::conv2d(module->pool(x), f.fc1_w, f.fc1_b);
  if (config.centre > 0) {
    const int c = config.centre, start = config.CentreStart();
    z = z + torch::conv2d(x.narrow(2, start, c).narrow(3, start, c),
                          f.fc1_centre_w);
  }
  return torch::relu(z.flatten(1));
}

torch::Tensor FoldedForward(const FoldedNet& f, IgbNetModule& module,
                            const NetworkConfig& config,
                            const torch::Tensor& input, bool bf16) {
  return module->fc2(FoldedEmbed(f, module, config, input, bf16));
}

namespace {

// The module with float32 parameters whatever the process's default dtype:
// a Python program's torch.set_default_dtype(torch.float64) (the same
// libtorch) made them float64, a model's float32 tensors loaded into them
// read as garbage ("tensor ... is not finite"), and a new network's
// initial weights differed. The default is set for the construction only.
IgbNetModule MakeModule(const NetworkConfig& config) {
  const caffe2::TypeMeta before = c10::get_default_dtype();
  c10::set_default_dtype(caffe2::TypeMeta::Make<float>());
  try {
    IgbNetModule module(config);
    c10::set_default_dtype(before);
    return module;
  } catch (...) {
    c10::set_default_dtype(before);
    throw;
  }
}

}  // namespace

TorchNet::TorchNet(const NetworkConfig& config, std::uint64_t seed)
    : TorchNet() {
  torch::manual_seed(seed);
  impl_->config = config;
  impl_->module = MakeModule(config);
  impl_->module->eval();
}

TorchNet::~TorchNet() = default;

const NetworkConfig& TorchNet::config() const { return impl_->config; }

const FileIdentity& TorchNet::file() const { return impl_->file; }

std::int64_t TorchNet::NumParameters() const {
  std::int64_t n = 0;
  for (const auto& p : impl_->module->parameters()) n += p.numel();
  return n;
}

std::unique_ptr<TorchNet> TorchNet::Load(const std::string& path,
                                         const std::string& error_file,
                                         int error_line,
                                         const std::string& key) {
  const auto fail = [&](const std::string& what) {
    return InputError(error_file, error_line, key, "'" + path + "': " + what);
  };
  std::error_code ec;
  if (const std::string kind = NonRegularKind(path); !kind.empty())
    throw fail("is " + kind + ", not a model file");
  if (!std::filesystem::is_regular_file(path, ec))
    throw fail("no such model file (train one with `aia train`)");
  // Read once: the bytes checked, hashed and loaded are the same.
  std::string bytes;
  try {
    bytes = ReadFile(path, std::uintmax_t{1} << 31);
  } catch (const std::bad_alloc&) {
    throw;  // out of memory is not bad input (cli.cc says it)
  } catch (const std::exception& e) {
    throw fail(std::string("not a readable model: ") + e.what());
  }
  // The container and every tensor's bytes, before libtorch sees them.
  if (const std::string damage = ArchiveDamage(bytes); !damage.empty())
    throw fail("not a readable model: " + damage);
  std::unique_ptr<TorchNet> net(new TorchNet());
  const std::filesystem::path absolute = std::filesystem::absolute(path, ec);
  net->impl_->file.path =
      (ec ? std::filesystem::path(path) : absolute).lexically_normal().string();
  net->impl_->file.sha256 = Sha256Hex(bytes);
  try {
    torch::serialize::InputArchive archive;
    archive.load_from(bytes.data(), bytes.size());
    torch::Tensor meta;
    if (!archive.try_read(kMetaKey, meta, /*is_buffer=*/true))
      throw std::runtime_error("not an aia I-GBNet model (no metadata)");
    meta = meta.to(torch::kUInt8).contiguous();
    const std::string json(reinterpret_cast<const char*>(meta.data_ptr()),
                           meta.numel());
    net->impl_->config = NetworkConfig::FromJson(json);
    net->impl_->module = MakeModule(net->impl_->config);
    // Loading replaces tensors whatever their shape: check them after.
    std::vector<std::pair<std::string, std::vector<int64_t>>> shapes;
    for (const auto& p : net->impl_->module->named_parameters())
      shapes.emplace_back(p.key(), p.value().sizes().vec());
    for (const auto& b : net->impl_->module->named_buffers())
      shapes.emplace_back(b.key(), b.value().sizes().vec());
    net->impl_->module->load(archive);
    auto params = net->impl_->module->named_parameters();
    auto buffers = net->impl_->module->named_buffers();
    for (const auto& [name, shape] : shapes) {
      const torch::Tensor* t = params.find(name);
      if (!t) t = buffers.find(name);
      if (!t || t->sizes().vec() != shape)
        throw std::runtime_error("tensor '" + name +
                                 "' does not match the model's metadata");
      if (t->is_floating_point() && !torch::isfinite(*t).all().item<bool>())
        throw std::runtime_error("tensor '" + name + "' is not finite");
    }
  } catch (const InputError&) {
    throw;
  } catch (const c10::Error& e) {
    std::string what = e.what_without_backtrace();
    const auto nl = what.find('\n');
    if (nl != std::string::npos) what.resize(nl);
    throw fail("not a readable model (" + what + ")");
  } catch (const std::bad_alloc&) {
    throw;  // out of memory is not bad input (cli.cc says it)
  } catch (const std::exception& e) {
    throw fail(e.what());
  }
  net->impl_->module->eval();
  return net;
}

void TorchNet::Save(const std::string& path) const {
  torch::serialize::OutputArchive archive;
  impl_->module->save(archive);
  const std::string json = impl_->config.ToJson();
  torch::Tensor meta =
      torch::empty({static_cast<int64_t>(json.size())}, torch::kUInt8);
  std::memcpy(meta.data_ptr(), json.data(), json.size());
  archive.write(kMetaKey, meta, /*is_buffer=*/true);
  SaveArchiveAtomic(archive, path);
}

void SaveArchiveAtomic(torch::serialize::OutputArchive& archive,
                       const std::string& path) {
  // Serialized into memory, then written by aia's own atomic writer: a
  // failed write (a full disk) is one "cannot write 'PATH': <errno text>"
  // error and leaves no temporary file, where libtorch's own file writer
  // aborts the process with a backtrace.
  std::string bytes;
  archive.save_to([&bytes](const void* data, std::size_t size) {
    bytes.append(static_cast<const char*>(data), size);
    return size;
  });
  WriteFileAtomic(path, bytes);
}

std::shared_ptr<const FoldedNet> TorchNet::Folded() const {
  std::lock_guard<std::mutex> lock(impl_->folded_mutex);
  if (!impl_->folded)
    impl_->folded =
        std::make_shared<const FoldedNet>(Fold(impl_->module, impl_->config));
  return impl_->folded;
}

void TorchNet::Infer(const float* images, int batch, int height, int width,
                     bool embed, bool bf16, float* out) const {
  AIA_CHECK(batch >= 0 && height > 0 && width > 0);
  // The centre is the robot's surroundings only in the window it was made
  // for (the centred frame's).
  AIA_CHECK(impl_->config.centre == 0 ||
            (height == impl_->config.channels.window &&
             width == impl_->config.channels.window));
  if (batch == 0) return;
  torch::NoGradGuard no_grad;
  const torch::Tensor x = torch::from_blob(
      const_cast<float*>(images),
      {batch, impl_->config.channels.num_channels(), height, width},
      torch::kFloat32);
  const std::shared_ptr<const FoldedNet> folded = Folded();
  const torch::Tensor y =
      (embed ? FoldedEmbed(*folded, impl_->module, impl_->config, x, bf16)
             : FoldedForward(*folded, impl_->module, impl_->config, x, bf16))
          .contiguous();
  std::memcpy(out, y.data_ptr<float>(), sizeof(float) * y.numel());
}

void TorchNet::Head(const float* features, const TeamGraph& graph,
                    float* logits) const {
  const int n = graph.rows();
  if (n == 0) return;
  // The training graph's layers on the whole team at once, on the calling
  // thread: S^k z in the graph's order, then M_k and fc2.
  torch::NoGradGuard no_grad;
  const GraphTensors g = ToTensors(graph);
  const torch::Tensor z = torch::from_blob(
      const_cast<float*>(features), {n, impl_->config.hidden}, torch::kFloat32);
  const torch::Tensor y = impl_->module->head(z, &g).contiguous();
  std::memcpy(logits, y.data_ptr<float>(), sizeof(float) * y.numel());
}

}  // namespace aia
