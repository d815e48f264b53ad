// Work on many points split across threads: the threads claim blocks of points in turn (sweeps of one
// axis and two, stacks of eigenvalue problems).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <exception>
#include <thread>
#include <vector>

#include "amb_fast/interrupt.hpp"

namespace amb_fast {

// Runs [0, count) in blocks of `grain` that the workers (<= 0: one per core) claim in turn: a worker the
// shared machine slows takes fewer blocks, so the threads end together (fixed halves wait for the slower).
// Each worker calls make_worker() once for its own state and then the returned work(begin, end) per block.
// The calling thread is a worker (the one that can see Ctrl-C), a thread each the others. A block's
// numbers do not depend on which worker runs it. After an error no more blocks are claimed; the first
// error is rethrown once all have stopped.
template <class MakeWorker>
void in_blocks(Eigen::Index count, Eigen::Index grain, int workers, MakeWorker&& make_worker) {
    if (workers <= 0) workers = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const Eigen::Index blocks = std::max<Eigen::Index>((count + grain - 1) / grain, 1);
    workers = static_cast<int>(std::min<Eigen::Index>(workers, blocks));
    const InterruptCheck* check = interrupt_check();
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(workers));
    std::atomic<Eigen::Index> next{0};
    auto worker = [&](int w) {
        const ScopedInterruptCheck installed(check);
        try {
            auto work = make_worker();
            for (Eigen::Index begin; (begin = next.fetch_add(grain)) < count;) {
                poll_interrupt();
                work(begin, std::min(begin + grain, count));
            }
        } catch (...) {
            errors[static_cast<std::size_t>(w)] = std::current_exception();
            next.store(count);  // the others stop at their next claim
        }
    };
    std::vector<std::thread> threads;
    for (int w = 1; w < workers; ++w) threads.emplace_back(worker, w);
    worker(0);
    for (auto& t : threads) t.join();
    for (auto& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace amb_fast
