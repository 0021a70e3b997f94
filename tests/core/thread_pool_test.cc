// The thread pool (core/thread_pool.h): every index called once, results
// that do not depend on the number of threads, exceptions, cancelling and a
// batch started in the background.
#include "aia/core/thread_pool.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace aia {
namespace {

using std::chrono::milliseconds;

TEST(ThreadPoolTest, KnownAnswerOnAnyNumberOfThreads) {
  // sum_{i<n} i^2 = (n - 1) n (2n - 1) / 6: for n = 1000, 332 833 500.
  for (int workers : {0, 1, 3}) {
    ThreadPool pool(workers);
    EXPECT_EQ(pool.workers(), workers);
    std::vector<std::int64_t> square(1000, -1);
    pool.Run(1000, [&](int i, int) { square[i] = std::int64_t{i} * i; });
    std::int64_t sum = 0;
    for (std::int64_t s : square) sum += s;
    EXPECT_EQ(sum, 332833500) << workers << " workers";
  }
}

TEST(ThreadPoolTest, EveryIndexOnceAndWorkersInRange) {
  for (int workers : {0, 1, 2, 5}) {
    ThreadPool pool(workers);
    // Several batches on one pool: each starts afresh.
    for (int n : {0, 1, 2, 7, 64, 1000}) {
      std::vector<std::atomic<int>> calls(n);
      std::atomic<int> bad_worker{0};
      pool.Run(n, [&](int i, int worker) {
        ++calls[i];
        // The caller and at most n - 1 of the pool's threads.
        if (worker < 0 || worker > std::min(workers, n - 1)) ++bad_worker;
      });
      for (int i = 0; i < n; ++i)
        ASSERT_EQ(calls[i].load(), 1) << "index " << i << " of " << n;
      EXPECT_EQ(bad_worker.load(), 0);
    }
  }
}

TEST(ThreadPoolTest, ManySmallBatchesInARow) {
  ThreadPool pool(3);
  long total = 0;
  for (int batch = 0; batch < 2000; ++batch) {
    std::vector<int> out(3, 0);
    pool.Run(3, [&](int i, int) { out[i] = i + 1; });
    total += out[0] + out[1] + out[2];
  }
  EXPECT_EQ(total, 2000L * 6);
}

TEST(ThreadPoolTest, TheFirstExceptionReachesTheCaller) {
  ThreadPool pool(2);
  std::atomic<int> calls{0};
  try {
    pool.Run(100, [&](int i, int) {
      ++calls;
      if (i == 40) throw std::runtime_error("index 40 failed");
    });
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "index 40 failed");
  }
  EXPECT_GE(calls.load(), 41);
  // The pool works on after a failure.
  std::atomic<int> after{0};
  pool.Run(10, [&](int, int) { ++after; });
  EXPECT_EQ(after.load(), 10);
}

TEST(ThreadPoolTest, StopOrFinishAfterAFailure) {
  // On the caller alone the order is 0, 1, 2, ...: a failure at 3 stops
  // before 4 (kStop), or every index still runs (kFinish), and the first
  // of two failures is the one rethrown.
  ThreadPool pool(0);
  std::vector<int> called;
  const auto task = [&](int i, int) {
    called.push_back(i);
    if (i == 3 || i == 5) throw std::runtime_error(std::to_string(i));
  };
  EXPECT_THROW(pool.Run(8, task, OnFailure::kStop), std::runtime_error);
  EXPECT_EQ(called, (std::vector<int>{0, 1, 2, 3}));
  called.clear();
  try {
    pool.Run(8, task, OnFailure::kFinish);
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "3");
  }
  EXPECT_EQ(called, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));
}

TEST(ThreadPoolTest, ACallCancelsItsBatch) {
  // One worker thread takes the indices in order: cancelled at 4, the
  // batch ends there.
  ThreadPool pool(1);
  std::vector<int> called;
  pool.Start(10, [&](int i, int worker) {
    EXPECT_EQ(worker, 1);  // the pool's own thread
    called.push_back(i);
    if (i == 4) pool.Cancel();
  });
  pool.Wait();
  EXPECT_EQ(called, (std::vector<int>{0, 1, 2, 3, 4}));
  // Cancelling with no batch under way does nothing to the next one.
  pool.Cancel();
  called.clear();
  pool.Run(3, [&](int i, int) { called.push_back(i); });
  EXPECT_EQ(called.size(), 3u);
}

TEST(ThreadPoolTest, AStartedBatchLeavesTheCallerFree) {
  ThreadPool pool(2);
  std::atomic<bool> release{false};
  std::atomic<int> done{0};
  pool.Start(4, [&](int, int) {
    while (!release) std::this_thread::sleep_for(milliseconds(1));
    ++done;
  });
  // The caller goes on while the batch waits.
  EXPECT_FALSE(pool.WaitFor(milliseconds(20)));
  EXPECT_EQ(done.load(), 0);
  release = true;
  pool.Wait();
  EXPECT_EQ(done.load(), 4);
  EXPECT_TRUE(pool.WaitFor(milliseconds(0)));
  // An exception of a started batch comes out of Wait().
  pool.Start(3, [](int i, int) {
    if (i == 1) throw std::invalid_argument("bad");
  });
  EXPECT_THROW(pool.Wait(), std::invalid_argument);
}

TEST(ThreadPoolTest, DestroyedWhileAStartedBatchRuns) {
  // The destructor cancels the rest and waits for the calls under way.
  std::atomic<int> done{0};
  {
    ThreadPool pool(1);
    pool.Start(1000, [&](int, int) {
      std::this_thread::sleep_for(milliseconds(1));
      ++done;
    });
    std::this_thread::sleep_for(milliseconds(5));
  }
  EXPECT_LT(done.load(), 1000);
}

TEST(ThreadPoolTest, ACallMayUseAnotherPool) {
  // Nested batches (the missions of a vector, each with the chunks of its
  // robots): 4 x 5 calls, every one once.
  ThreadPool outer(2);
  std::vector<std::atomic<int>> calls(20);
  outer.Run(4, [&](int i, int) {
    ThreadPool inner(1);
    inner.Run(5, [&](int j, int) { ++calls[i * 5 + j]; });
  });
  for (const auto& c : calls) EXPECT_EQ(c.load(), 1);
}

TEST(ThreadPoolTest, ResultsPerIndexDoNotDependOnTheThreads) {
  // A per-index result (a small hash of i) is the same on 0, 1 and 4
  // worker threads, whatever thread computed it.
  const auto compute = [](int workers) {
    ThreadPool pool(workers);
    std::vector<std::uint64_t> out(513);
    pool.Run(513, [&](int i, int) {
      std::uint64_t h = 1469598103934665603ull;
      for (int r = 0; r <= i % 17; ++r) h = (h ^ (i + r)) * 1099511628211ull;
      out[i] = h;
    });
    return out;
  };
  const auto one = compute(0);
  EXPECT_EQ(compute(1), one);
  EXPECT_EQ(compute(4), one);
}

}  // namespace
}  // namespace aia
