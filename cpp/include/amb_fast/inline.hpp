// AMB_FAST_ALWAYS_INLINE: for the kernels called once per sample inside the loops.
#pragma once

// Kernels called once per sample inside the loops: inlined whatever the compiler's size heuristics say
// (left out of line, a control law was called through the PLT with its state in memory).
#if defined(__GNUC__) || defined(__clang__)
#define AMB_FAST_ALWAYS_INLINE __attribute__((always_inline)) inline
#elif defined(_MSC_VER)
#define AMB_FAST_ALWAYS_INLINE __forceinline
#else
#define AMB_FAST_ALWAYS_INLINE inline
#endif
