// Errors of the core, two kinds kept apart (as pbrt-v4 keeps ErrorExit and CHECK):
//  - bad input from the user: require() throws InvalidArgument (or the code throws
//    IoError for files); the bindings translate them into ValueError / OSError;
//  - broken invariants of the core itself: GS_CHECK(cond) prints where and aborts, since no
//    caller can recover from a bug (it stays on in release builds: the checks are cheap).
#pragma once
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace gigascroll {

struct InvalidArgument : std::invalid_argument {
    using std::invalid_argument::invalid_argument;
};

struct IoError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Throws InvalidArgument(message) unless cond holds.
inline void require(bool cond, const std::string& message) {
    if (!cond) throw InvalidArgument(message);
}

namespace detail {
[[noreturn]] inline void check_failed(const char* condition, const char* file, int line) {
    std::fprintf(stderr, "gigascroll: internal check failed: %s (%s:%d)\n", condition, file, line);
    std::abort();
}
}  // namespace detail

}  // namespace gigascroll

#define GS_CHECK(cond) \
    ((cond) ? static_cast<void>(0) : ::gigascroll::detail::check_failed(#cond, __FILE__, __LINE__))

namespace gigascroll {

}  // namespace gigascroll
