#include "aia/core/thread_pool.h"

#include <algorithm>
#include <limits>
#include <utility>

#include "aia/core/check.h"

namespace aia {
namespace {

// next_ once a batch is cancelled: beyond every n, with room for the
// fetch_adds of every thread that still looks.
constexpr long kCancelled = std::numeric_limits<long>::max() / 2;

}  // namespace

ThreadPool::ThreadPool(int workers) {
  AIA_CHECK(workers >= 0);
  threads_.reserve(workers);
  for (int w = 1; w <= workers; ++w)
    threads_.emplace_back([this, w] { Loop(w); });
}

ThreadPool::~ThreadPool() {
  Cancel();
  {
    std::unique_lock<std::mutex> lock(mu_);
    finished_.wait(lock, [this] { return busy_ == 0; });
    quit_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void ThreadPool::Begin(int n, TaskRef f, OnFailure on_failure, int helpers) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    AIA_CHECK_MSG(!in_batch_, "one batch at a time on a ThreadPool");
    in_batch_ = true;
    task_ = f;
    n_ = n;
    on_failure_ = on_failure;
    helpers_ = helpers;
    next_.store(0);
    busy_ = helpers;
    failure_ = nullptr;
    if (helpers > 0) ++generation_;
  }
  if (helpers > 0) wake_.notify_all();
}

void ThreadPool::Work(int worker) {
  // Indices are only handed out here; what the calls write is published to
  // the caller of Finish() by mu_ (busy_ is counted down under it).
  for (;;) {
    const long i = next_.fetch_add(1, std::memory_order_relaxed);
    if (i >= n_) return;
    try {
      task_(static_cast<int>(i), worker);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mu_);
      if (!failure_) failure_ = std::current_exception();
      if (on_failure_ == OnFailure::kStop) next_.store(kCancelled);
    }
  }
}

void ThreadPool::Loop(int worker) {
  std::uint64_t seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mu_);
      wake_.wait(lock, [&] { return quit_ || generation_ != seen; });
      if (quit_) return;
      seen = generation_;
      if (worker > helpers_) continue;  // not needed for this batch
    }
    Work(worker);
    std::lock_guard<std::mutex> lock(mu_);
    if (--busy_ == 0) finished_.notify_all();
  }
}

void ThreadPool::Finish() {
  std::exception_ptr failure;
  {
    std::unique_lock<std::mutex> lock(mu_);
    finished_.wait(lock, [this] { return busy_ == 0; });
    in_batch_ = false;
    task_ = TaskRef();
    std::swap(failure, failure_);
  }
  if (failure) std::rethrow_exception(failure);
}

void ThreadPool::RunRef(int n, TaskRef f, OnFailure on_failure) {
  if (n <= 0) return;
  Begin(n, f, on_failure, std::min(workers(), n - 1));
  Work(0);
  Finish();
}

void ThreadPool::Start(int n, Task f, OnFailure on_failure) {
  AIA_CHECK_MSG(!threads_.empty(), "ThreadPool::Start needs a worker thread");
  {
    std::lock_guard<std::mutex> lock(mu_);
    AIA_CHECK_MSG(!in_batch_, "one batch at a time on a ThreadPool");
    owned_ = std::move(f);
  }
  n = std::max(n, 0);
  // At least one thread even with nothing to do, so that Wait() has a
  // batch to end.
  Begin(n, TaskRef(owned_), on_failure, std::max(1, std::min(workers(), n)));
}

bool ThreadPool::WaitFor(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  return finished_.wait_for(lock, timeout, [this] { return busy_ == 0; });
}

void ThreadPool::Wait() {
  try {
    Finish();
  } catch (...) {
    owned_ = nullptr;
    throw;
  }
  owned_ = nullptr;  // what the task holds goes now, not at the next batch
}

void ThreadPool::Cancel() { next_.store(kCancelled); }

}  // namespace aia
