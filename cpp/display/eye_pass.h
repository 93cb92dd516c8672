// One eye's display pass over its rows (DisplayPass::render_eye): the pieces it shares with
// the pass's frame set-up.
#pragma once
#include <cstdint>

namespace gigascroll {
namespace display {

// A fresh number (never 0) for each frame any DisplayPass renders and each render_eye call.
std::uint64_t next_serial();

}  // namespace display
}  // namespace gigascroll
