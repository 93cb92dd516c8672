// Bounded queue behind one mutex: the baseline the lock-free queues are measured against,
// with the same try_push / try_pop / batch interface, plus blocking pop and push for worker
// pools (the Unreal-style loader baseline).
#pragma once
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <utility>

namespace gigascroll {

template <typename T>
class LockedQueue {
public:
    explicit LockedQueue(std::size_t capacity) : capacity_(capacity < 1 ? 1 : capacity) {}

    std::size_t capacity() const { return capacity_; }

    template <typename U>
    [[nodiscard]] bool try_push(U&& value) {
        {
            std::lock_guard lock(mutex_);
            if (items_.size() >= capacity_) return false;
            items_.push_back(std::forward<U>(value));
        }
        not_empty_.notify_one();
        return true;
    }

    template <typename It>
    [[nodiscard]] std::size_t try_push_batch(It first, std::size_t n) {
        std::size_t k = 0;
        {
            std::lock_guard lock(mutex_);
            for (; k < n && items_.size() < capacity_; ++k, ++first) items_.push_back(std::move(*first));
        }
        if (k == 1) not_empty_.notify_one();
        if (k > 1) not_empty_.notify_all();
        return k;
    }

    [[nodiscard]] bool try_pop(T& out) {
        {
            std::lock_guard lock(mutex_);
            if (items_.empty()) return false;
            out = std::move(items_.front());
            items_.pop_front();
        }
        not_full_.notify_one();
        return true;
    }

    template <typename OutIt>
    [[nodiscard]] std::size_t try_pop_batch(OutIt out, std::size_t max) {
        std::size_t k = 0;
        {
            std::lock_guard lock(mutex_);
            for (; k < max && !items_.empty(); ++k, ++out) {
                *out = std::move(items_.front());
                items_.pop_front();
            }
        }
        if (k) not_full_.notify_all();
        return k;
    }

    // Blocks until an element arrives or close() was called; false when closed and empty.
    bool wait_pop(T& out) {
        {
            std::unique_lock lock(mutex_);
            not_empty_.wait(lock, [&] { return !items_.empty() || closed_; });
            if (items_.empty()) return false;
            out = std::move(items_.front());
            items_.pop_front();
        }
        not_full_.notify_one();
        return true;
    }

    // Blocks until there is room or close() was called; false (value untouched) when closed.
    template <typename U>
    bool wait_push(U&& value) {
        {
            std::unique_lock lock(mutex_);
            not_full_.wait(lock, [&] { return items_.size() < capacity_ || closed_; });
            if (closed_) return false;
            items_.push_back(std::forward<U>(value));
        }
        not_empty_.notify_one();
        return true;
    }

    // Wakes every thread blocked in wait_pop / wait_push; try_push still succeeds afterwards.
    void close() {
        {
            std::lock_guard lock(mutex_);
            closed_ = true;
        }
        not_empty_.notify_all();
        not_full_.notify_all();
    }

    std::size_t size() const {
        std::lock_guard lock(mutex_);
        return items_.size();
    }

    bool empty() const {
        std::lock_guard lock(mutex_);
        return items_.empty();
    }

private:
    const std::size_t capacity_;
    mutable std::mutex mutex_;
    std::condition_variable not_empty_, not_full_;
    std::deque<T> items_;
    bool closed_ = false;
};

}  // namespace gigascroll
