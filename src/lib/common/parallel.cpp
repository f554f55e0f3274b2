// The library's thread pool (see parallel.hpp).
#include "common/parallel.hpp"

#include <algorithm>
#include <condition_variable>
#include <exception>
#include <limits>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace mcg::parallel {

namespace {

/// The jobs of one for_each call. Guarded by the pool's mutex.
struct Batch {
  const std::function<void(std::size_t)>* job = nullptr;
  std::size_t count = 0;
  std::size_t next = 0;     ///< the next job to hand out
  std::size_t running = 0;  ///< handed out and not finished
  std::exception_ptr error;
  bool open() const { return next < count && !error; }
  bool finished() const { return !open() && running == 0; }
};

}  // namespace

struct Pool::State {
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<Batch*> queued;  ///< batches with jobs to hand out, oldest first
  std::vector<std::thread> workers;
  bool closing = false;
  State* outer = nullptr;  ///< the creating thread's pool before this one

  /// Hands out a job of the newest open batch (the innermost work first).
  bool take(Batch*& batch, std::size_t& k) {
    std::erase_if(queued, [](const Batch* b) { return !b->open(); });
    if (queued.empty()) return false;
    batch = queued.back();
    k = batch->next++;
    ++batch->running;
    return true;
  }

  /// Runs job k of `batch` with the lock released; wakes the waiters when the batch ends.
  void run(Batch& batch, std::size_t k, std::unique_lock<std::mutex>& lock) {
    lock.unlock();
    std::exception_ptr error;
    try {
      (*batch.job)(k);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    if (error && !batch.error) batch.error = error;
    --batch.running;
    if (batch.finished()) changed.notify_all();
  }

  void work();
  void wait_for(Batch& batch);
};

namespace {

/// The pool whose thread this is (its creator or one of its workers), if any.
thread_local Pool::State* current = nullptr;

/// Makes `state` the calling thread's pool until the scope ends.
class Current {
 public:
  explicit Current(Pool::State* state) : saved_(current) { current = state; }
  ~Current() { current = saved_; }
  Current(const Current&) = delete;
  Current& operator=(const Current&) = delete;

 private:
  Pool::State* saved_;
};

}  // namespace

void Pool::State::work() {
  const Current here(this);
  std::unique_lock lock(mutex);
  for (;;) {
    Batch* batch = nullptr;
    std::size_t k = 0;
    if (take(batch, k)) {
      run(*batch, k, lock);
    } else if (closing) {
      return;
    } else {
      changed.wait(lock);
    }
  }
}

void Pool::State::wait_for(Batch& batch) {
  std::unique_lock lock(mutex);
  queued.push_back(&batch);
  changed.notify_all();
  while (!batch.finished()) {
    Batch* other = nullptr;
    std::size_t k = 0;
    if (take(other, k)) {
      run(*other, k, lock);
    } else {
      changed.wait(lock);
    }
  }
  std::erase(queued, &batch);
}

unsigned worker_count(unsigned requested, std::size_t jobs) {
  const unsigned n = requested != 0 ? requested : std::max(1U, std::thread::hardware_concurrency());
  return static_cast<unsigned>(std::min<std::size_t>(n, std::max<std::size_t>(jobs, 1)));
}

Pool::Pool(unsigned threads) : state_(std::make_unique<State>()) {
  const unsigned n = worker_count(threads, std::numeric_limits<std::size_t>::max());
  try {
    for (unsigned w = 1; w < n; ++w) state_->workers.emplace_back([s = state_.get()] { s->work(); });
  } catch (const std::system_error&) {
    // Out of threads: the workers that started, and the creating thread, share the jobs.
  }
  state_->outer = current;
  current = state_.get();
}

Pool::~Pool() {
  {
    const std::lock_guard lock(state_->mutex);
    state_->closing = true;
  }
  state_->changed.notify_all();
  for (auto& t : state_->workers) t.join();
  current = state_->outer;
}

unsigned Pool::size() const { return static_cast<unsigned>(state_->workers.size()) + 1; }

void for_each(std::size_t count, unsigned threads, const std::function<void(std::size_t)>& job) {
  if (count == 0) return;
  Batch batch;
  batch.job = &job;
  batch.count = count;
  if (current == nullptr || threads == 1) {
    if (worker_count(threads, count) == 1) {
      for (std::size_t k = 0; k < count; ++k) job(k);
      return;
    }
    const Pool pool(worker_count(threads, count));
    current->wait_for(batch);
  } else {
    current->wait_for(batch);
  }
  if (batch.error) std::rethrow_exception(batch.error);
}

}  // namespace mcg::parallel
