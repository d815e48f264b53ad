// MimoLoop::run: the chunks' noise and inputs, and the SIMD kernel (portable and AVX2) that advances
// every sample of a chunk.
#include "amb_fast/mimo.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
#include "amb_fast/lanes.hpp"

namespace amb_fast {

void MimoLoop::run(const double* const* force, Eigen::Index n, double* const* recorded, double* const* out) {
    const Eigen::Index p = model_.forces(), q = model_.probes();
    for (Eigen::Index start = 0; start < n; start += chunk) {
        poll_interrupt();
        const Eigen::Index m = std::min(chunk, n - start);
        for (Eigen::Index l = 0; l < lanes_; ++l) {
            for (Eigen::Index j = 0; j < q; ++j)
                if (model_.sensor_noise[j] > 0.0)
                    sensor_rng_[l * q + j].fill(sensor_draws_[l].col(j).data(), m, model_.sensor_noise[j]);
            for (Eigen::Index j = 0; j < p; ++j)
                if (model_.force_noise[j] > 0.0)
                    force_rng_[l * p + j].fill(force_draws_[l].col(j).data(), m, model_.force_noise[j]);
        }
        // The chunk's inputs [f; n] x lanes, sample-major.
        for (Eigen::Index l = 0; l < lanes_; ++l)
            for (Eigen::Index k = 0; k < m; ++k) {
                double* in = inputs_.data() + k * (p + q) * lanes_ + l;
                const double* f = force[l] + (start + k) * p;
                for (Eigen::Index j = 0; j < p; ++j) in[j * lanes_] = f[j];
                for (Eigen::Index j = 0; j < q; ++j) in[(p + j) * lanes_] = sensor_draws_[l](k, j);
            }
        if (lanes_ == 2) run_block<2>(force, start, m, recorded, out);
        else run_block<1>(force, start, m, recorded, out);
        // Inf and NaN never turn finite again in a linear recursion: one check per chunk.
        for (Eigen::Index i = 0; i < rows_ * lanes_; ++i) {
            if (std::isfinite(w_[static_cast<std::size_t>(i)])) continue;
            std::ostringstream msg;
            msg << "the state became non-finite by sample " << k_ + start + m << ": the loop is unstable";
            throw std::overflow_error(msg.str());
        }
    }
    k_ += n;
}

namespace {
// Four slots in one SIMD register (GCC/Clang vector extension): two 16-byte halves in a portable build,
// one 32-byte register in the AVX2 kernel. Loads and stores go through memcpy (no alignment assumed).
typedef double Quad __attribute__((vector_size(32)));
typedef double Pair __attribute__((vector_size(16)));
typedef double PairU __attribute__((vector_size(16), aligned(8), may_alias));
typedef double QuadU __attribute__((vector_size(32), aligned(8), may_alias));  // for unaligned stores

struct Step {
    Eigen::Index states, forces, probes, outputs, passes, m, start;
    const int *pass_inputs, *pass_states, *offsets;
    const Eigen::Index* output_position;  // of each output row
    const double* coefficients;
    const double* in;  // the chunk's inputs, (forces + probes) x lanes per sample
    double *w, *next;  // [z; o; padding] x lanes, swapped every sample
    const double* const* force;
    double* const* recorded;
    double* const* out;
    const double* pole;
    double* transducer;  // [lane][channel], 8 per lane
    const double* const* force_noise;
    Eigen::Index noise_stride;
};

// A column's value in every slot: (v0, v1, v0, v1) for two lanes, (v, v, v, v) for one. (Through a
// pointer: a function returning a 32-byte vector would change the ABI without AVX.)
template <int K>
__attribute__((always_inline)) inline void column(const double* x, Quad* value) {
    if constexpr (K == 2) {
        Pair pair;
        std::memcpy(&pair, x, sizeof pair);
        *value = __builtin_shufflevector(pair, pair, 0, 1, 0, 1);
    } else {
        const double v = *x;
        *value = Quad{v, v, v, v};
    }
}

// Adds `count` columns of x (at x + offsets[j], K values each) times their coefficients (P blocks of four
// each, from c) to the sums: even columns to `even`, odd ones to `odd` (two short chains, not one long one).
template <int K, int P>
__attribute__((always_inline)) inline void accumulate(const double* x, int count, const int*& offsets, const double*& c,
                                                      Quad* even, Quad* odd) {
    const Quad zero = {0.0, 0.0, 0.0, 0.0};
    Quad v = zero, value = zero;
    int j = 0;
    for (; j + 1 < count; j += 2, c += 8 * P, offsets += 2) {
        column<K>(x + offsets[0], &value);
        for (int b = 0; b < P; ++b) {
            std::memcpy(&v, c + 4 * b, sizeof v);
            even[b] += v * value;
        }
        column<K>(x + offsets[1], &value);
        for (int b = 0; b < P; ++b) {
            std::memcpy(&v, c + 4 * (P + b), sizeof v);
            odd[b] += v * value;
        }
    }
    if (j < count) {
        column<K>(x + offsets[0], &value);
        for (int b = 0; b < P; ++b) {
            std::memcpy(&v, c + 4 * b, sizeof v);
            even[b] += v * value;
        }
        c += 4 * P;
        ++offsets;
    }
}

// The whole chunk: every sample, the map by passes of P blocks kept in registers (inputs first, then
// states, each column's coefficients times its value added to every block), the outputs, and the
// transducers. The same source is compiled twice (portable, AVX2), so both kernels do the same IEEE
// operations in the same order.
template <int K, int P>
__attribute__((always_inline)) inline void advance(Step& st) {
    const Eigen::Index p = st.forces, r = st.outputs, ni = st.forces + st.probes;
    double* w = st.w;
    double* next = st.next;
    const Quad zero = {0.0, 0.0, 0.0, 0.0};
    for (Eigen::Index k = 0; k < st.m; ++k) {
        const double* in = st.in + k * ni * K;
        const double* c = st.coefficients;
        const int* offsets = st.offsets;
        for (Eigen::Index pass = 0; pass < st.passes; ++pass) {
            Quad even[P], odd[P];
            for (int b = 0; b < P; ++b) even[b] = odd[b] = zero;
            accumulate<K, P>(in, st.pass_inputs[pass], offsets, c, even, odd);
            accumulate<K, P>(w, st.pass_states[pass], offsets, c, even, odd);
            // Stored in 16-byte halves, as the next sample loads them (a load from part of a wider
            // store is not forwarded from it on every processor).
            for (int b = 0; b < P; ++b) {
                const Quad sum = even[b] + odd[b];
                double* to = next + (pass * P + b) * 4;
                *reinterpret_cast<PairU*>(to) = __builtin_shufflevector(sum, sum, 0, 1);
                *reinterpret_cast<PairU*>(to + 2) = __builtin_shufflevector(sum, sum, 2, 3);
            }
        }
        std::swap(w, next);
        const Eigen::Index sample = st.start + k;
        for (int l = 0; l < K; ++l) {
            double* o = st.out[l] + sample * r;
            for (Eigen::Index i = 0; i < r; ++i) o[i] = w[st.output_position[i] * K + l];
            const double* f = st.force[l] + sample * p;
            double* rec = st.recorded[l] + sample * p;
            double* qs = st.transducer + 8 * l;
            for (Eigen::Index j = 0; j < p; ++j) {
                const double a = st.pole[j];
                double value = f[j];
                if (a > 0.0) {
                    value -= qs[j];
                    qs[j] = a * qs[j] + (1.0 - a) * f[j];
                }
                rec[j] = value + st.force_noise[l][k + j * st.noise_stride];
            }
        }
    }
    st.w = w;
    st.next = next;
}

template <int K, int P>
void advance_portable(Step& st) {
    advance<K, P>(st);
}

#if AMB_FAST_WIDE_LANES
template <int K, int P>
__attribute__((target("avx2"))) void advance_avx2(Step& st) {
    advance<K, P>(st);
}
#endif

template <int K, int P>
void advance_any(Step& st) {
#if AMB_FAST_WIDE_LANES
    if (simd_avx2()) return advance_avx2<K, P>(st);
#endif
    advance_portable<K, P>(st);
}

template <int K>
void advance_lanes(Step& st, int pass) {
    switch (pass) {
        case 1:
            return advance_any<K, 1>(st);
        case 2:
            return advance_any<K, 2>(st);
        default:
            return advance_any<K, 4>(st);
    }
}
}  // namespace

template <int K>
void MimoLoop::run_block(const double* const* force, Eigen::Index start, Eigen::Index m, double* const* recorded,
                         double* const* out) {
    const Eigen::Index p = model_.forces();
    require(p <= 8, "force channels", p, "at most 8");
    double transducer[2 * 8] = {};
    const double* noise[2];
    for (int l = 0; l < K; ++l) {
        noise[l] = force_draws_[l].data();
        for (Eigen::Index j = 0; j < p; ++j) transducer[8 * l + j] = q_(j, l);
    }
    Step st{model_.states(),
            p,
            model_.probes(),
            model_.outputs(),
            passes_,
            m,
            start,
            pass_inputs_.data(),
            pass_states_.data(),
            offsets_.data(),
            position_.data() + model_.states(),
            coefficients_.data(),
            inputs_.data(),
            w_.data(),
            next_.data(),
            force,
            recorded,
            out,
            model_.transducer_pole.data(),
            transducer,
            noise,
            chunk};
    advance_lanes<K>(st, pass_);
    if (st.w != w_.data()) w_.swap(next_);  // an odd number of samples: the state is in the other buffer
    for (int l = 0; l < K; ++l)
        for (Eigen::Index j = 0; j < p; ++j) q_(j, l) = transducer[8 * l + j];
}

}  // namespace amb_fast
