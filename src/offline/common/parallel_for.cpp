#include "common/parallel_for.h"

#include <algorithm>
#include <atomic>
#include <string>
#include <system_error>

#include <sched.h>

#include "common/input_error.h"

namespace shtool {

int max_threads() {
  const int hw = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  return std::max(64, 8 * hw);
}

int usable_cores() {
  // The CPUs this process may run on: under taskset, a Slurm cpuset or mpirun's binding
  // that is fewer than the machine has, and more threads would only take turns.
  cpu_set_t set;
  CPU_ZERO(&set);
  if (::sched_getaffinity(0, sizeof set, &set) == 0) {
    const int n = CPU_COUNT(&set);
    if (n > 0) return n;
  }
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

int resolve_threads(int requested) {
  if (requested < 0) throw InputError("--threads must be 0 (every core) or more, got " + std::to_string(requested));
  if (requested == 0) return usable_cores();
  if (requested > max_threads())
    throw InputError("--threads " + std::to_string(requested) + " is more than this machine can use (at most " +
                     std::to_string(max_threads()) + ")");
  return requested;
}

ThreadPool::ThreadPool(int threads) : threads_(std::max(1, threads)) {
  try {
    for (int t = 1; t < threads_; ++t) workers_.emplace_back([this, t] { work(t); });
  } catch (const std::system_error& e) {
    const int started = static_cast<int>(workers_.size()) + 1;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
      ++round_;
    }
    wake_.notify_all();
    for (std::thread& w : workers_) w.join();
    throw InputError("cannot start " + std::to_string(threads_) + " threads (started " + std::to_string(started) +
                     "): " + e.what() + "; ask for fewer with --threads");
  }
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    ++round_;
  }
  wake_.notify_all();
  for (std::thread& w : workers_) w.join();
}

void ThreadPool::run(std::size_t count, const std::function<void(int, std::size_t, std::size_t)>& f) {
  const int active = static_cast<int>(std::max<std::size_t>(1, std::min<std::size_t>(threads_, count)));
  if (active == 1) {
    f(0, 0, count);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &f;
    count_ = count;
    active_ = active;
    pending_ = active - 1;
    error_ = nullptr;
    ++round_;
  }
  wake_.notify_all();
  std::exception_ptr mine;
  try {
    f(0, 0, count / active);
  } catch (...) {
    mine = std::current_exception();
  }
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return pending_ == 0; });
  job_ = nullptr;
  if (!mine) mine = error_;
  error_ = nullptr;
  lock.unlock();
  if (mine) std::rethrow_exception(mine);
}

void ThreadPool::work(int worker) {
  long long seen = 0;
  for (;;) {
    const std::function<void(int, std::size_t, std::size_t)>* job = nullptr;
    std::size_t count = 0;
    int active = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return round_ != seen; });
      seen = round_;
      if (stop_) return;
      if (worker >= active_) continue;
      job = job_;
      count = count_;
      active = active_;
    }
    std::exception_ptr error;
    try {
      (*job)(worker, count * worker / active, count * (worker + 1) / active);
    } catch (...) {
      error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (error && !error_) error_ = error;
      --pending_;
    }
    done_.notify_one();
  }
}

void parallel_for(std::size_t count, int threads, const std::function<void(std::size_t)>& body,
                  const std::function<void(std::size_t, std::size_t)>& progress) {
  ThreadPool pool(static_cast<int>(std::min<std::size_t>(std::max(1, threads), std::max<std::size_t>(count, 1))));
  std::atomic<std::size_t> done{0};
  std::atomic<bool> failed{false};
  pool.run(count, [&](int worker, std::size_t begin, std::size_t end) {
    try {
      std::size_t local = 0;
      for (std::size_t i = begin; i < end && !failed.load(std::memory_order_relaxed); ++i) {
        body(i);
        if (++local == 64) {
          done += local;
          local = 0;
          if (worker == 0 && progress) progress(done.load(), count);
        }
      }
      done += local;
    } catch (...) {
      failed = true;
      throw;
    }
  });
  if (progress) progress(count, count);
}

}  // namespace shtool
