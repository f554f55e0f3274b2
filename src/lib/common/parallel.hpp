// The one thread pool of the library: independent jobs spread over worker threads, with
// any exception a job throws carried back to the caller.
#pragma once

#include <cstddef>
#include <functional>

namespace mcg::parallel {

/// Threads to use for `jobs` jobs when `requested` are asked for (0 = every core):
/// min(requested or the core count, jobs), at least 1.
unsigned worker_count(unsigned requested, std::size_t jobs);

/// Calls job(k) for every k in [0, count) on worker_count(threads, count) threads (the
/// calling thread is one of them), each k exactly once, taken in increasing order. When a
/// job throws (any exception), no further job starts; the running ones finish, and the first
/// exception is rethrown in the caller once every worker has joined.
void for_each(std::size_t count, unsigned threads, const std::function<void(std::size_t)>& job);

}  // namespace mcg::parallel
