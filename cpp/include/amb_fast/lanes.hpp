// Several loops run side by side, one per SIMD lane: every lane performs exactly the operations of a
// single run in the same order (IEEE-754 arithmetic is the same in a lane as in a scalar register,
// and the core is compiled without fused multiply-add), so each lane gives the digits of its own
// run. The loop's cost is the latency of its sample-to-sample chain, not its arithmetic, so four
// independent chains interleaved cost little more than one.
#pragma once

#include <cstddef>

namespace amb_fast {

#if defined(__GNUC__) || defined(__clang__)
#define AMB_FAST_LANES_OK 1
constexpr int loop_lanes = 2;
using LaneVector = double __attribute__((vector_size(sizeof(double) * loop_lanes)));
using LaneMask = decltype(LaneVector{} < LaneVector{});  // -1 in a lane where a comparison holds, else 0

// x in every lane, exactly (0.0 + x would turn -0.0 into +0.0).
inline LaneVector lane_broadcast(double x) {
    LaneVector v;
    for (int g = 0; g < loop_lanes; ++g) v[g] = x;
    return v;
}
// std::clamp(v, -limit, limit) and std::max(a, std::abs(b)) lane by lane, with the same results.
inline LaneVector lane_clamp(LaneVector v, double limit) {
    const LaneVector high = LaneVector{} + limit, low = LaneVector{} - limit;  // exact: 0 +- limit
    const LaneVector raised = v < low ? low : v;
    return high < raised ? high : raised;
}
inline LaneVector lane_max_abs(LaneVector a, LaneVector b) {
    const LaneVector magnitude = b < LaneVector{} ? -b : b;
    return a < magnitude ? magnitude : a;
}
#else
#define AMB_FAST_LANES_OK 0
constexpr int loop_lanes = 1;  // no portable SIMD vector type: loops run one at a time
#endif

}  // namespace amb_fast
