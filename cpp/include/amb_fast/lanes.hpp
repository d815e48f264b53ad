// Several loops run side by side, one per SIMD lane: every lane performs exactly the operations of a
// single run in the same order (IEEE-754 arithmetic is the same in a lane as in a scalar register,
// and the core is compiled without fused multiply-add), so each lane gives the digits of its own
// run. The loop's cost is the latency of its sample-to-sample chain, not its arithmetic, so
// independent chains interleaved cost little more than one.
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>
#include <new>

#include "amb_fast/inline.hpp"

namespace amb_fast {

#if defined(__GNUC__) || defined(__clang__)
#define AMB_FAST_LANES_OK 1
// K doubles in one vector: two fill an SSE2/NEON register (every 64-bit build has them); four fill an
// AVX2 register, used only where the processor reports AVX2 at run time (wide_lanes_available).
// (A dependent vector_size on an alias template is ignored by GCC, hence one specialisation per K.)
template <int K>
struct LaneType;
template <>
struct LaneType<2> {
    typedef double type __attribute__((vector_size(2 * sizeof(double))));
};
// Outside AVX2 code GCC aligns a 4-double vector to 16 bytes, while AVX2 code loads and stores it as
// aligned to 32: every object of it that the AVX2 kernel touches is put at a 32-byte boundary by hand
// (alignas on variables, LaneArray for arrays, vectors first in structs).
template <>
struct LaneType<4> {
    typedef double type __attribute__((vector_size(4 * sizeof(double))));
};
template <int K>
using Lanes = typename LaneType<K>::type;
// The same lanes as 64-bit unsigned integers (random.hpp's generators side by side).
template <int K>
struct LaneWordType;
template <>
struct LaneWordType<2> {
    typedef unsigned long long type __attribute__((vector_size(2 * sizeof(double))));
};
template <>
struct LaneWordType<4> {
    typedef unsigned long long type __attribute__((vector_size(4 * sizeof(double))));
};
template <int K>
using LaneWords = typename LaneWordType<K>::type;
using LaneVector = Lanes<2>;
constexpr int loop_lanes = 2;
#if defined(__x86_64__) || defined(_M_X64)
#define AMB_FAST_WIDE_LANES 1
constexpr int wide_lanes = 4;
inline bool wide_lanes_available() {
    static const bool yes = __builtin_cpu_supports("avx2");
    return yes;
}
#else
constexpr int wide_lanes = loop_lanes;
inline bool wide_lanes_available() { return false; }
#endif

// x in every lane of v, exactly (0.0 + x would turn -0.0 into +0.0). By reference: a 32-byte vector
// passed by value would change the calling convention between builds with and without AVX.
template <class V>
AMB_FAST_ALWAYS_INLINE void lane_fill(V& v, double x) {
    for (std::size_t g = 0; g < sizeof(V) / sizeof(double); ++g) v[g] = x;
}
// std::clamp(v, -limit, limit) and std::max(a, std::abs(b)) lane by lane, with the same results.
template <class V>
AMB_FAST_ALWAYS_INLINE V lane_clamp(V v, double limit) {
    V high, low;
    lane_fill(high, limit);
    lane_fill(low, -limit);
    const V raised = v < low ? low : v;
    return high < raised ? high : raised;
}
template <class V>
AMB_FAST_ALWAYS_INLINE V lane_max_abs(V a, V b) {
    const V magnitude = b < V{} ? -b : b;
    return a < magnitude ? magnitude : a;
}
#else
#define AMB_FAST_LANES_OK 0
constexpr int loop_lanes = 1;  // no portable SIMD vector type: loops run one at a time
constexpr int wide_lanes = 1;
inline bool wide_lanes_available() { return false; }
#endif

// n values of T at an address aligned to sizeof(T) (at least to alignof(T)): std::vector only
// guarantees alignof(T), which for a lane vector built outside AVX2 code is less than AVX2 assumes.
template <class T>
class LaneArray {
  public:
    LaneArray() = default;
    explicit LaneArray(std::size_t n) { resize(n); }
    void resize(std::size_t n) {
        data_.reset(n ? static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(alignment))) : nullptr);
        for (std::size_t k = 0; k < n; ++k) data_[k] = T{};
        size_ = n;
    }
    T* data() { return data_.get(); }
    std::size_t size() const { return size_; }
    T& operator[](std::size_t k) { return data_[k]; }
    const T& operator[](std::size_t k) const { return data_[k]; }

  private:
    static constexpr std::size_t alignment = sizeof(T) > alignof(T) ? sizeof(T) : alignof(T);
    struct Free {
        void operator()(T* p) const { ::operator delete(p, std::align_val_t(alignment)); }
    };
    std::unique_ptr<T[], Free> data_;
    std::size_t size_ = 0;
};

// Which build of the SIMD kernels runs (the MIMO loop's step, the per-line Hessenberg solves): chosen
// at run time (AVX2 where the processor has it, on x86-64), or forced, for tests. Both give
// bit-identical results (the same operations in the same order; no fused multiply-add).
enum class SimdKernel { automatic, portable, avx2 };
inline std::atomic<int>& forced_simd_kernel() {
    static std::atomic<int> kernel{static_cast<int>(SimdKernel::automatic)};
    return kernel;
}
// avx2 falls back to portable where the processor lacks it.
inline void set_simd_kernel(SimdKernel kernel) {
    forced_simd_kernel().store(static_cast<int>(kernel), std::memory_order_relaxed);
}
inline bool simd_avx2() {
    return static_cast<SimdKernel>(forced_simd_kernel().load(std::memory_order_relaxed)) != SimdKernel::portable &&
           wide_lanes_available();
}
// The build automatic picks here: "avx2" or "portable".
inline const char* simd_kernel_name() { return wide_lanes_available() ? "avx2" : "portable"; }

// How many loops run side by side on this processor.
inline int lanes_available() { return wide_lanes_available() ? wide_lanes : loop_lanes; }

}  // namespace amb_fast
