// The batch room's one worker pool and one shard rule.

#include "overtake/batch/pool.hpp"
#include "overtake/batch/shard.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "overtake/base/errors.hpp"

namespace overtake::batch {
namespace {

using ::testing::HasSubstr;

// A gate the test opens: items wait at it, so that the test, not the clock, says when an item
// finishes.
class Gate {
 public:
  void open(std::size_t item) {
    const std::lock_guard lock(mu_);
    open_.push_back(item);
    cv_.notify_all();
  }
  void open_all() {
    const std::lock_guard lock(mu_);
    all_ = true;
    cv_.notify_all();
  }
  // Waits until `item` may pass; false when the pool halted first.
  bool wait(std::size_t item, const std::atomic<bool>* halt) {
    std::unique_lock lock(mu_);
    for (;;) {
      if (all_ || std::find(open_.begin(), open_.end(), item) != open_.end()) return true;
      if (halt->load()) return false;
      cv_.wait_for(lock, std::chrono::milliseconds(5));
    }
  }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::vector<std::size_t> open_;
  bool all_ = false;
};

TEST(Pool, ByIndexDeliversInIndexOrderWhateverOrderItemsFinish) {
  Gate gate;
  std::vector<std::size_t> seen;
  std::atomic<int> started{0};
  // Items finish in reverse order: 3 first, then 2, 1, 0.
  const PoolEnd end = run_pool<std::size_t>(
      4, {4, nullptr, PoolOrder::by_index, {}},
      [&](std::size_t i, const std::atomic<bool>* halt) {
        if (++started == 4) gate.open(3);
        EXPECT_TRUE(gate.wait(i, halt));
        if (i > 0) gate.open(i - 1);
        return i * 10;
      },
      [&](std::size_t i, std::size_t&& r) {
        EXPECT_EQ(r, i * 10);
        seen.push_back(i);
        return true;
      });
  EXPECT_EQ(seen, (std::vector<std::size_t>{0, 1, 2, 3}));
  EXPECT_EQ(end.delivered, 4U);
  EXPECT_FALSE(end.stopped);
}

TEST(Pool, AsFinishedDeliversEachAsItComes) {
  Gate gate;
  std::vector<std::size_t> seen;
  std::atomic<int> started{0};
  (void)run_pool<int>(
      2, {2, nullptr, PoolOrder::as_finished, {}},
      [&](std::size_t i, const std::atomic<bool>* halt) {
        if (++started == 2) gate.open(1);  // item 1 finishes while item 0 waits
        EXPECT_TRUE(gate.wait(i, halt));
        return 0;
      },
      [&](std::size_t i, int&& /*r*/) {
        seen.push_back(i);
        if (i == 1) gate.open(0);
        return true;
      });
  EXPECT_EQ(seen, (std::vector<std::size_t>{1, 0}));
}

TEST(Pool, StopStartsNoMoreItemsAndHaltsThoseInProgress) {
  std::atomic<bool> stop{false};
  std::atomic<int> ran{0};
  std::vector<bool> results;
  const PoolEnd end = run_pool<bool>(
      1000, {2, &stop, PoolOrder::by_index, {}},
      [&](std::size_t i, const std::atomic<bool>* halt) {
        ++ran;
        if (i == 3) stop = true;
        if (i < 3) return true;
        // An item in progress ends once the pool halts it (as a drive given the flag does).
        while (!halt->load()) std::this_thread::yield();
        return false;
      },
      [&](std::size_t /*i*/, bool&& finished) {
        results.push_back(finished);
        return true;
      });
  EXPECT_TRUE(end.stopped);
  EXPECT_LE(ran.load(), 5);  // items 0-3 and at most the one the other thread had taken
  ASSERT_GE(results.size(), 4U);
  EXPECT_EQ(std::vector<bool>(results.begin(), results.begin() + 4),
            (std::vector<bool>{true, true, true, false}));
}

TEST(Pool, TheConsumerEndsThePool) {
  std::atomic<int> ran{0};
  const PoolEnd end = run_pool<int>(
      100000, {3, nullptr, PoolOrder::by_index, {}},
      [&](std::size_t /*i*/, const std::atomic<bool>* /*halt*/) { return ++ran; },
      [&](std::size_t i, int&& /*r*/) { return i < 9; });
  EXPECT_TRUE(end.ended_by_consumer);
  EXPECT_EQ(end.delivered, 10U);
  EXPECT_LT(ran.load(), 100000);
}

TEST(Pool, AnExceptionInAnItemReachesTheCallerInItsPlace) {
  std::vector<std::size_t> seen;
  try {
    (void)run_pool<int>(
        20, {4, nullptr, PoolOrder::by_index, {}},
        [&](std::size_t i, const std::atomic<bool>* /*halt*/) {
          if (i == 5) throw std::runtime_error("item 5 failed");
          return 0;
        },
        [&](std::size_t i, int&& /*r*/) {
          seen.push_back(i);
          return true;
        });
    FAIL() << "the exception was lost";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "item 5 failed");
  }
  // In index order, the items before it were delivered, and none after it.
  EXPECT_EQ(seen, (std::vector<std::size_t>{0, 1, 2, 3, 4}));
}

TEST(Pool, AnExceptionInTheConsumerReachesTheCaller) {
  EXPECT_THROW((void)run_pool<int>(
                   10, {2, nullptr, PoolOrder::as_finished, {}},
                   [](std::size_t /*i*/, const std::atomic<bool>* /*halt*/) { return 0; },
                   [](std::size_t /*i*/, int&& /*r*/) -> bool { throw std::logic_error("no"); }),
               std::logic_error);
}

TEST(Pool, RunsAtMostJobsItemsAtOnceAndRefusesJobsOutOfRange) {
  std::atomic<int> running{0};
  std::atomic<int> most{0};
  std::size_t delivered = 0;
  (void)run_pool<int>(
      50, {3, nullptr, PoolOrder::as_finished, {}},
      [&](std::size_t /*i*/, const std::atomic<bool>* /*halt*/) {
        const int now = ++running;
        int seen = most.load();
        while (now > seen && !most.compare_exchange_weak(seen, now)) {
        }
        std::this_thread::yield();
        --running;
        return 0;
      },
      [&](std::size_t /*i*/, int&& /*r*/) {
        ++delivered;
        return true;
      });
  EXPECT_EQ(delivered, 50U);
  EXPECT_LE(most.load(), 3);
  for (const int jobs : {0, -1, kMaxJobs + 1}) {
    try {
      check_jobs(jobs);
      ADD_FAILURE() << jobs << " jobs accepted";
    } catch (const base::UsageError& e) {
      EXPECT_THAT(e.what(), HasSubstr("--jobs must be between 1 and " + std::to_string(kMaxJobs)));
    }
  }
  EXPECT_THROW((void)run_pool<int>(
                   1, {kMaxJobs + 1, nullptr, PoolOrder::as_finished, {}},
                   [](std::size_t /*i*/, const std::atomic<bool>* /*halt*/) { return 0; },
                   [](std::size_t /*i*/, int&& /*r*/) { return true; }),
               base::UsageError);
}

TEST(Pool, NoItemsEndAtOnce) {
  const PoolEnd end = run_pool<int>(
      0, {4, nullptr, PoolOrder::by_index, {}},
      [](std::size_t /*i*/, const std::atomic<bool>* /*halt*/) { return 0; },
      [](std::size_t /*i*/, int&& /*r*/) { return true; });
  EXPECT_EQ(end.delivered, 0U);
}

TEST(Shard, HoldsEveryNthItemAndTheShardsTogetherHoldEachOnce) {
  for (int count = 1; count <= 5; ++count) {
    for (std::size_t total = 0; total <= 13; ++total) {
      std::vector<int> owners(total, 0);
      for (int index = 1; index <= count; ++index) {
        const Shard shard{index, count};
        std::size_t held = 0;
        for (std::size_t k = 0; k < total; ++k) {
          if (!shard.holds(k)) continue;
          EXPECT_EQ(shard.item(held), k);
          ++held;
          ++owners[k];
        }
        EXPECT_EQ(shard.size_of(total), held) << shard.text() << " of " << total;
      }
      for (const int n : owners) EXPECT_EQ(n, 1);
    }
  }
  EXPECT_EQ((Shard{1, 4}).size_of(10), 3U);
  EXPECT_EQ((Shard{3, 4}).size_of(10), 2U);
  EXPECT_EQ((Shard{8, 8}).size_of(280), 35U);
}

TEST(Shard, ParsesIOverN) {
  EXPECT_EQ(parse_shard("2/8"), (Shard{2, 8}));
  EXPECT_EQ(parse_shard("1/1").text(), "1/1");
  for (const char* bad : {"0/8", "9/8", "2-8", "2/8x", "/8", "a/b", ""}) {
    EXPECT_THROW((void)parse_shard(bad), base::UsageError) << bad;
  }
  EXPECT_THROW(check_shard({3, 2}), base::UsageError);
  EXPECT_NO_THROW(check_shard({2, 2}));
}

}  // namespace
}  // namespace overtake::batch
