#pragma once
// A parallel map whose results come out in input order: the scan's determinism with worker
// threads. One mutex guards the input queue and the finished results; the producer blocks while
// `capacity` items wait to be started (finished results wait for pop(), which the producer
// calls between pushes).
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace builtscene::barcode {

template <class In, class Out>
class OrderedPool {
 public:
  OrderedPool(int threads, std::size_t capacity, std::function<Out(In&)> work)
      : capacity_(std::max<std::size_t>(1, capacity)), work_(std::move(work)) {
    for (int t = 0; t < std::max(1, threads); ++t) threads_.emplace_back([this] { run(); });
  }
  ~OrderedPool() {
    close();
    for (auto& t : threads_) t.join();
  }
  OrderedPool(const OrderedPool&) = delete;
  OrderedPool& operator=(const OrderedPool&) = delete;

  void push(In in) {
    std::unique_lock lock(mutex_);
    space_.wait(lock, [&] { return queue_.size() < capacity_; });
    queue_.emplace_back(pushed_++, std::move(in));
    lock.unlock();
    work_ready_.notify_one();
  }
  // The next result in input order if it is finished (wait = false) or once it is (wait = true).
  // False when nothing is pending (or, without waiting, when the next one is not finished).
  bool pop(Out& out, bool wait) {
    std::unique_lock lock(mutex_);
    if (popped_ == pushed_) return false;
    if (wait) done_ready_.wait(lock, [&] { return done_.count(popped_) > 0; });
    auto it = done_.find(popped_);
    if (it == done_.end()) return false;
    out = std::move(it->second);
    done_.erase(it);
    ++popped_;
    lock.unlock();
    space_.notify_all();
    return true;
  }
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    work_ready_.notify_all();
  }

 private:
  void run() {
    while (true) {
      std::pair<std::size_t, In> item;
      {
        std::unique_lock lock(mutex_);
        work_ready_.wait(lock, [&] { return closed_ || !queue_.empty(); });
        if (queue_.empty()) return;
        item = std::move(queue_.front());
        queue_.pop_front();
      }
      space_.notify_all();
      Out out = work_(item.second);
      {
        std::lock_guard lock(mutex_);
        done_.emplace(item.first, std::move(out));
      }
      done_ready_.notify_all();
    }
  }

  std::size_t capacity_;
  std::function<Out(In&)> work_;
  std::mutex mutex_;
  std::condition_variable work_ready_, done_ready_, space_;
  std::deque<std::pair<std::size_t, In>> queue_;
  std::map<std::size_t, Out> done_;
  std::size_t pushed_ = 0, popped_ = 0;
  bool closed_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace builtscene::barcode
