// The learned policy's threads (learning/network.h: PolicyThreads,
// ParallelFor) on the project's thread pool (core/thread_pool.h): no torch
// here; a worker sets libtorch's threads only when the plugin is loaded (a
// network exists).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <memory>

#include "aia/core/thread_pool.h"
#include "aia/learning/network.h"
#include "torch_backend.h"

namespace aia {

namespace {

std::atomic<int> policy_threads{1};

// The pool of the calling thread, kept from call to call (a thread made per
// call costs more than it saves), with PolicyThreads() - 1 threads of its
// own. Per calling thread, so that callers on several threads (missions
// stepped in parallel) never wait for each other, as when each call made
// its own threads.
ThreadPool& CallerPool(int workers) {
  thread_local std::unique_ptr<ThreadPool> pool;
  thread_local pid_t owner = 0;
  if (owner != ::getpid()) {
    // In a child forked since (Python's multiprocessing), the threads are
    // gone: the pool is left behind, never joined.
    (void)pool.release();
    owner = ::getpid();
  }
  if (!pool || pool->workers() != workers)
    pool = std::make_unique<ThreadPool>(workers);
  return *pool;
}

// libtorch (its OpenMP team too) runs single-threaded on the pool's threads:
// nested teams spin against each other on two cores. Set once per thread,
// as soon as the plugin is loaded.
void SingleThreadedTorch() {
  thread_local bool single = false;
  if (single) return;
  if (const TorchBackend* torch = TorchIfLoaded()) {
    torch->set_threads(1);
    single = true;
  }
}

}  // namespace

void SetPolicyThreads(int threads) {
  if (threads > 0) policy_threads = threads;
}

int PolicyThreads() { return policy_threads; }

const RangeRunner& PolicyRunner() {
  static const RangeRunner run = [](int n, const RangeTask& f) {
    ParallelFor(n, 16, f);
  };
  return run;
}

void PrepareCallerTorchThreads(int chunks) {
  const int threads = PolicyThreads();
  if (threads <= 1) return;
  const int want = chunks <= 1 ? threads : 1;
  thread_local int set_to = 0;
  if (want == set_to) return;
  if (const TorchBackend* torch = TorchIfLoaded()) {
    torch->set_threads(want);
    set_to = want;
  }
}

void ParallelFor(int n, int grain,
                 const std::function<void(int, int, int)>& f) {
  if (n <= 0) return;
  grain = std::max(1, grain);
  const int chunks = (n + grain - 1) / grain;
  const int threads = PolicyThreads();
  if (std::min(threads, chunks) <= 1) {
    f(0, n, 0);
    return;
  }
  // The chunks depend on n and grain alone, never on the threads.
  CallerPool(threads - 1).Run(chunks, [&](int c, int worker) {
    if (worker > 0) SingleThreadedTorch();
    f(c * grain, std::min(n, (c + 1) * grain), worker);
  });
}

}  // namespace aia
