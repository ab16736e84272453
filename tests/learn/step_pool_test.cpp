// The learning environment's threads: every item once, a worker index of its own per thread,
// uneven items shared by who is free, and an exception ending the call.

#include "overtake/learn/step_pool.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace {

using overtake::learn::StepPool;

TEST(LearnStepPool, EveryItemRunsOnceAndNoTwoAtOnceShareAWorker) {
  StepPool pool(3);
  ASSERT_EQ(pool.threads(), 3U);
  for (const std::size_t count : {0UL, 1UL, 2UL, 7UL, 64UL}) {
    std::vector<std::atomic<int>> runs(count);
    std::vector<std::atomic<int>> inside(pool.threads());
    std::atomic<bool> shared_worker{false};
    std::atomic<bool> bad_worker{false};
    pool.run(count, [&](std::size_t i, std::size_t worker) {
      if (worker >= pool.threads()) {
        bad_worker = true;
        return;
      }
      if (inside[worker].fetch_add(1) != 0) shared_worker = true;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      runs[i].fetch_add(1);
      inside[worker].fetch_sub(1);
    });
    for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(runs[i].load(), 1) << "item " << i;
    EXPECT_FALSE(bad_worker) << count << " items";
    EXPECT_FALSE(shared_worker) << count << " items";
  }
}

TEST(LearnStepPool, AThreadHeldUpByASlowItemLeavesTheRestToTheOther) {
  // Item 0 takes 200 ms, the other 63 a fraction of a millisecond each. Shared as contiguous
  // halves, the thread of item 0 would also run items 1-31 after it; taken as each thread is
  // free, the other thread runs nearly all of them while the first is held up.
  StepPool pool(2);
  std::mutex mu;
  std::vector<std::set<std::size_t>> by_worker(2);
  pool.run(64, [&](std::size_t i, std::size_t worker) {
    std::this_thread::sleep_for(i == 0 ? std::chrono::microseconds(200000)
                                       : std::chrono::microseconds(200));
    const std::lock_guard lock(mu);
    by_worker[worker].insert(i);
  });
  ASSERT_EQ(by_worker[0].size() + by_worker[1].size(), 64U);
  const std::size_t slow_one = by_worker[0].count(0) == 1 ? 0 : 1;
  EXPECT_GT(by_worker[1 - slow_one].size(), 48U)
      << "the thread of the slow item ran " << by_worker[slow_one].size() << " items";
}

TEST(LearnStepPool, AnExceptionIsRethrownAndNoFurtherItemIsTaken) {
  StepPool pool(2);
  std::atomic<int> ran{0};
  EXPECT_THROW(pool.run(1000,
                        [&](std::size_t i, std::size_t /*worker*/) {
                          ran.fetch_add(1);
                          if (i == 3) throw std::runtime_error("item 3 failed");
                          std::this_thread::sleep_for(std::chrono::microseconds(100));
                        }),
               std::runtime_error);
  // The items taken before the failure was seen finish; no thread takes many more.
  EXPECT_LT(ran.load(), 100);
  // The pool serves the next call as before.
  std::atomic<int> after{0};
  pool.run(10, [&](std::size_t /*i*/, std::size_t /*worker*/) { after.fetch_add(1); });
  EXPECT_EQ(after.load(), 10);
}

}  // namespace
