// Stopping a long computation from outside (Ctrl-C in Python): the bindings install a check for the
// duration of a call; the loops ask it between blocks of samples and periods. The core itself knows
// nothing of Python.
#pragma once

#include <functional>
#include <stdexcept>

namespace amb_fast {

// Returns true when the computation is to stop. Called from the computing threads, so it must be
// cheap and thread-safe.
using InterruptCheck = std::function<bool()>;

struct Interrupted : std::runtime_error {
    Interrupted() : std::runtime_error("amb_fast: the computation was interrupted") {}
};

namespace detail {
inline const InterruptCheck*& current_interrupt_check() {
    thread_local const InterruptCheck* check = nullptr;
    return check;
}
}  // namespace detail

// The check in force on this thread (or null).
inline const InterruptCheck* interrupt_check() { return detail::current_interrupt_check(); }

// Throws Interrupted if the check in force says so.
inline void poll_interrupt() {
    const InterruptCheck* check = detail::current_interrupt_check();
    if (check && (*check)()) throw Interrupted();
}

// Installs a check on this thread for its lifetime (threads started by the core install their
// caller's).
class ScopedInterruptCheck {
  public:
    explicit ScopedInterruptCheck(const InterruptCheck* check) : previous_(detail::current_interrupt_check()) {
        detail::current_interrupt_check() = check;
    }
    ~ScopedInterruptCheck() { detail::current_interrupt_check() = previous_; }
    ScopedInterruptCheck(const ScopedInterruptCheck&) = delete;
    ScopedInterruptCheck& operator=(const ScopedInterruptCheck&) = delete;

  private:
    const InterruptCheck* previous_;
};

}  // namespace amb_fast
