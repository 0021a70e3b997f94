// The learned policy's threads (learning/network.h: PolicyThreads,
// ParallelFor): no torch here; a worker sets libtorch's threads only when
// the plugin is loaded (a network exists).
#include <algorithm>
#include <atomic>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "aia/learning/network.h"
#include "torch_backend.h"

namespace aia {

namespace {
std::atomic<int> policy_threads{1};
}  // namespace

void SetPolicyThreads(int threads) {
  if (threads > 0) policy_threads = threads;
}

int PolicyThreads() { return policy_threads; }

void ParallelFor(int n, int grain,
                 const std::function<void(int, int, int)>& f) {
  if (n <= 0) return;
  grain = std::max(1, grain);
  const int chunks = (n + grain - 1) / grain;
  const int workers = std::min(PolicyThreads(), chunks);
  if (workers <= 1) {
    f(0, n, 0);
    return;
  }
  std::atomic<int> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  const auto work = [&](int worker) {
    // This thread's libtorch (its OpenMP team too) runs single-threaded.
    const TorchBackend* torch = TorchIfLoaded();
    if (worker > 0 && torch) torch->set_threads(1);
    try {
      for (int c = next++; c < chunks; c = next++)
        f(c * grain, std::min(n, (c + 1) * grain), worker);
    } catch (...) {
      std::lock_guard<std::mutex> lock(failure_mutex);
      if (!failure) failure = std::current_exception();
      next = chunks;
    }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < workers; ++w) pool.emplace_back(work, w);
  work(0);
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace aia
