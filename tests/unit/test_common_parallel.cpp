// The thread pool: every job runs once, the thread count is honoured, and any exception a
// job throws reaches the caller.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
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

TEST(CommonParallel, NothingToDo) {
  bool called = false;
  for_each(0, 4, [&](std::size_t) { called = true; });
  EXPECT_FALSE(called);
}

}  // namespace
}  // namespace mcg::parallel
