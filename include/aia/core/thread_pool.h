// The one thread pool of the project: threads kept for the pool's life that
// run batches of indexed calls. Used by `aia eval` (its instances), the
// Python package's VectorMissions (its missions) and the learned policy's
// ParallelFor (its chunks of robots).
//
// Results never depend on the number of threads as long as what a call
// writes depends on its index alone (each index is called once, whichever
// thread takes it): the indices are handed out in increasing order to
// whichever thread is free, and the worker number a call gets is only for
// scratch memory of that thread.
#ifndef AIA_CORE_THREAD_POOL_H_
#define AIA_CORE_THREAD_POOL_H_

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace aia {

// A way to run f(begin, end, worker) over [0, n) on threads, workers
// numbered from 0 (learning/network.h's ParallelFor is one); an empty
// runner means f(0, n, 0). Work split so must write per index only, so that
// the result does not depend on the split.
using RangeTask = std::function<void(int begin, int end, int worker)>;
using RangeRunner = std::function<void(int n, const RangeTask& f)>;

// Runs f over [0, n) with `run`, or at once where it is empty.
inline void RunRange(const RangeRunner& run, int n, const RangeTask& f) {
  if (n <= 0) return;
  if (run) {
    run(n, f);
  } else {
    f(0, n, 0);
  }
}

// What a batch does once one of its calls has thrown.
enum class OnFailure {
  kStop,    // hands out no further index; the calls under way finish
  kFinish,  // calls every index still (a failed mission must not keep the
            // others of a vector from stepping)
};

class ThreadPool {
 public:
  // f(index, worker): worker 0 is the thread that called Run, 1 ..
  // workers() the pool's own.
  using Task = std::function<void(int index, int worker)>;

  // Keeps `workers` threads (0 or more) until destroyed: a thread made per
  // batch costs more than it saves (glibc sets up an arena and a cache for
  // each new thread).
  explicit ThreadPool(int workers);
  // Cancels a batch started and not waited for, waits for its calls under
  // way, and joins the threads.
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int workers() const { return static_cast<int>(threads_.size()); }

  // Calls f(i, worker) once for each i in [0, n), on the calling thread
  // (worker 0) and at most n - 1 of the pool's threads, each taking the next
  // index when it is free; returns when every call has returned. The first
  // exception a call throws is rethrown here, after the others have
  // returned; with kStop the indices not yet handed out are not called. One
  // batch at a time: Run and Start must not overlap on one pool (a call may
  // use another pool). `f` is called by reference: nothing is allocated per
  // batch.
  template <typename F>
  void Run(int n, F&& f, OnFailure on_failure = OnFailure::kStop) {
    RunRef(n, TaskRef(f), on_failure);
  }

  // The same on the pool's threads alone (at least one), returning at once,
  // so that the caller stays free (aia eval watches for Ctrl-C meanwhile).
  // End it with Wait().
  void Start(int n, Task f, OnFailure on_failure = OnFailure::kStop);
  // Whether the started batch has ended, waiting up to `timeout` for it.
  bool WaitFor(std::chrono::milliseconds timeout);
  // Waits until the started batch has ended, then rethrows the first
  // exception a call threw.
  void Wait();

  // Hands out no further index of the batch under way (the calls under way
  // finish); a call may cancel its own batch. Nothing happens without one.
  void Cancel();

 private:
  // A callable by reference, without std::function's copy.
  class TaskRef {
   public:
    TaskRef() = default;
    template <typename F, typename = std::enable_if_t<
                              !std::is_same_v<std::decay_t<F>, TaskRef>>>
    explicit TaskRef(F& f)
        : object_(const_cast<void*>(static_cast<const void*>(&f))),
          call_([](void* o, int i, int w) {
            (*static_cast<std::remove_reference_t<F>*>(o))(i, w);
          }) {}
    void operator()(int index, int worker) const {
      call_(object_, index, worker);
    }

   private:
    void* object_ = nullptr;
    void (*call_)(void*, int, int) = nullptr;
  };

  void RunRef(int n, TaskRef f, OnFailure on_failure);
  // Sets up a batch for `helpers` of the pool's threads.
  void Begin(int n, TaskRef f, OnFailure on_failure, int helpers);
  void Work(int worker);
  void Loop(int worker);
  void Finish();  // waits for the pool's threads; rethrows the failure

  std::vector<std::thread> threads_;
  std::mutex mu_;
  std::condition_variable wake_, finished_;
  // The batch, set under mu_ before generation_ moves on.
  TaskRef task_;
  bool in_batch_ = false;  // from Begin to Finish
  Task owned_;             // Start's copy of its task
  long n_ = 0;
  OnFailure on_failure_ = OnFailure::kStop;
  int helpers_ = 0;  // the pool's threads 1 .. helpers_ take part
  std::atomic<long> next_{0};
  int busy_ = 0;  // pool threads still in the batch
  std::uint64_t generation_ = 0;
  bool quit_ = false;
  std::exception_ptr failure_;  // under mu_
};

}  // namespace aia

#endif  // AIA_CORE_THREAD_POOL_H_
