// Exceptions thrown by the core. The bindings translate them into Python exceptions:
// InvalidArgument -> ValueError, IoError -> OSError. Anything else -> RuntimeError.
#pragma once
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

}  // namespace gigascroll
