// The thread pool: every job runs once, the thread count is honoured, any exception a job
// throws reaches the caller, and work spread inside a job shares the pool's threads.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "test_support_error.hpp"

namespace mcg::parallel {
namespace {

TEST(CommonParallel, WorkerCount) {
  EXPECT_EQ(worker_count(3, 10), 3U);
  EXPECT_EQ(worker_count(8, 2), 2U);
  EXPECT_EQ(worker_count(4, 0), 1U);
  EXPECT_EQ(worker_count(0, 1000), std::max(1U, std::thread::hardware_concurrency()));
}

TEST(CommonParallel, EveryJobOnceOnAtMostTheRequestedThreads) {
  for (unsigned threads : {1U, 2U, 3U}) {
    std::vector<std::atomic<int>> runs(200);
    std::mutex mutex;
    std::set<std::thread::id> ids;
    for_each(runs.size(), threads, [&](std::size_t k) {
      ++runs[k];
      const std::lock_guard lock(mutex);
      ids.insert(std::this_thread::get_id());
      // Hold the job so that every worker gets one.
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    });
    for (const auto& r : runs) EXPECT_EQ(r.load(), 1);
    EXPECT_EQ(ids.size(), threads) << threads << " threads requested";
    if (threads == 1) {
      EXPECT_EQ(*ids.begin(), std::this_thread::get_id());
    }
  }
}

TEST(CommonParallel, ErrorFromAWorkerReachesTheCaller) {
  EXPECT_EQ(test::error_of([] {
              for_each(50, 2, [](std::size_t k) {
                if (k == 17) fail("job {} failed", k);
              });
            }),
            "job 17 failed");
}

TEST(CommonParallel, AnyExceptionReachesTheCallerAndStopsNewJobs) {
  std::atomic<std::size_t> started{0};
  EXPECT_THROW(for_each(10000, 2,
                        [&](std::size_t k) {
                          ++started;
                          if (k == 3) throw std::bad_alloc();
                          if (k == 5) throw std::runtime_error("not an mcg::Error");
                        }),
               std::exception);
  EXPECT_LT(started.load(), 10000U);
}

/// Thread ids seen by jobs, and a wait until `count` distinct ones have run a job (10 s at
/// most: a pool that never lends a second thread fails instead of hanging).
struct Threads {
  std::mutex mutex;
  std::condition_variable seen;
  std::set<std::thread::id> ids;
  void enter() {
    const std::lock_guard lock(mutex);
    ids.insert(std::this_thread::get_id());
    seen.notify_all();
  }
  void wait_for(std::size_t count) {
    std::unique_lock lock(mutex);
    seen.wait_for(lock, std::chrono::seconds(10), [&] { return ids.size() >= count; });
  }
};

TEST(CommonParallel, NestedWorkSharesThePoolsThreadsAndNoneIdles) {
  const Pool pool(2);
  ASSERT_EQ(pool.size(), 2U);
  Threads all;
  Threads inner;
  std::atomic<int> leaves{0};
  // Two outer jobs, the first done at once: the second's inner jobs must get both threads
  // (each waits until two threads have run inner jobs), and nothing makes a third thread.
  for_each(2, 0, [&](std::size_t outer) {
    all.enter();
    if (outer == 0) return;
    for_each(6, 0, [&](std::size_t) {
      all.enter();
      inner.enter();
      inner.wait_for(2);
      for_each(3, 0, [&](std::size_t) {
        all.enter();
        ++leaves;
      });
    });
  });
  EXPECT_EQ(inner.ids.size(), 2U);
  EXPECT_EQ(all.ids.size(), 2U);
  EXPECT_EQ(leaves.load(), 18);
}

TEST(CommonParallel, InsideAPoolOneThreadStaysInTheCaller) {
  const Pool pool(2);
  for_each(2, 0, [&](std::size_t) {
    const auto caller = std::this_thread::get_id();
    for_each(20, 1, [&](std::size_t) { EXPECT_EQ(std::this_thread::get_id(), caller); });
  });
}

TEST(CommonParallel, AnErrorDeepInsideAPoolReachesTheOutermostCaller) {
  const Pool pool(2);
  EXPECT_EQ(test::error_of([] {
              for_each(4, 0, [](std::size_t) {
                for_each(30, 0, [](std::size_t k) {
                  if (k == 11) fail("inner job {} failed", k);
                });
              });
            }),
            "inner job 11 failed");
  // The pool is still usable afterwards.
  std::atomic<int> count{0};
  for_each(10, 0, [&](std::size_t) { ++count; });
  EXPECT_EQ(count.load(), 10);
}

TEST(CommonParallel, NothingToDo) {
  bool called = false;
  for_each(0, 4, [&](std::size_t) { called = true; });
  EXPECT_FALSE(called);
}

}  // namespace
}  // namespace mcg::parallel
