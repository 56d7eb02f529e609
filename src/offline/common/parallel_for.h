// The offline jobs' one way of using every core. Work is split into a fixed contiguous
// partition of [0, count) and each item writes its result by index, so what is computed
// never depends on the thread count; exceptions thrown by the body reach the caller
// (the first one, after every worker has stopped).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace shtool {

// The most threads a job may ask for: hardware threads times a small factor (more only
// add switching, and thousands exhaust the process limit).
int max_threads();
// The CPUs this process may run on (its affinity mask: taskset, cpusets, mpirun's
// binding), at least 1.
int usable_cores();
// The count a job runs with: `requested` (0: usable_cores()), checked against
// max_threads(). Throws InputError for a request below 0 or above max_threads().
int resolve_threads(int requested);

// Persistent workers for jobs made of many parallel steps (a GA generation has several),
// where starting threads for each step would cost more than the step.
class ThreadPool {
 public:
  // Starts threads - 1 workers (the caller's thread is worker 0). A failure to start a
  // thread stops the ones already started and throws InputError.
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return threads_; }

  // f(worker, begin, end) on min(threads, count) workers; worker w gets
  // [count * w / active, count * (w + 1) / active).
  void run(std::size_t count, const std::function<void(int, std::size_t, std::size_t)>& f);

 private:
  void work(int worker);

  int threads_ = 1;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(int, std::size_t, std::size_t)>* job_ = nullptr;
  std::size_t count_ = 0;
  int active_ = 0, pending_ = 0;
  long long round_ = 0;
  bool stop_ = false;
  std::exception_ptr error_;
};

// One-shot form: body(i) for every i in [0, count) on `threads` threads.
// progress(done, count), when given, is called from the caller's thread now and then.
void parallel_for(std::size_t count, int threads, const std::function<void(std::size_t)>& body,
                  const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace shtool
