// The one thread pool of the library: independent jobs spread over worker threads, with
// any exception a job throws carried back to the caller. Jobs may themselves spread work
// (a search's candidates, each candidate's Jacobian columns, each column's runs): the inner
// jobs go to the same workers, never to a pool of their own.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>

namespace mcg::parallel {

/// Threads to use for `jobs` jobs when `requested` are asked for (0 = every core):
/// min(requested or the core count, jobs), at least 1.
unsigned worker_count(unsigned requested, std::size_t jobs);

/// A set of worker threads that every for_each call made inside it shares: while a Pool
/// lives, for_each called on its creating thread or inside any job it runs queues its jobs on
/// these workers (whatever `threads` it asks for, except 1: that stays in the caller). The
/// newest queued jobs are taken first, so a job's own inner work finishes before further
/// outer jobs start; a caller waiting for its jobs takes any queued job meanwhile, so no
/// worker idles while work is queued.
class Pool {
 public:
  /// worker_count(threads, unlimited) threads in all, the creating thread being one of them
  /// (it must also be the one that destroys the pool).
  explicit Pool(unsigned threads);
  ~Pool();
  Pool(const Pool&) = delete;
  Pool& operator=(const Pool&) = delete;
  /// Threads in all.
  unsigned size() const;

  struct State;

 private:
  std::unique_ptr<State> state_;
};

/// Calls job(k) for every k in [0, count), each k exactly once, taken in increasing order.
/// Inside a Pool (see there) the pool's threads run them; otherwise worker_count(threads,
/// count) threads do (the calling thread is one of them), and jobs that spread work of their
/// own share those threads. When a job throws (any exception), no further job of this call
/// starts; the running ones finish, and the first exception is rethrown in the caller once
/// they have.
void for_each(std::size_t count, unsigned threads, const std::function<void(std::size_t)>& job);

}  // namespace mcg::parallel
