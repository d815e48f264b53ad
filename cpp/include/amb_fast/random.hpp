// Measurement noise: a fast, exactly reproducible stream of normal deviates.
//
// Generator: xoshiro256++ (D. Blackman, S. Vigna, "Scrambled linear pseudorandom number generators",
// ACM Trans. Math. Softw. 47(4), 2021; reference code at https://prng.di.unimi.it/xoshiro256plusplus.c),
// its state filled from the 64-bit seed by splitmix64, as its authors recommend.
// Normal deviates: the 256-layer ziggurat of G. Marsaglia, W. W. Tsang, "The ziggurat method for
// generating random variables", J. Stat. Softw. 5(8), 2000, in its 64-bit form with the layer, the
// sign and a 52-bit abscissa taken from disjoint bits of one draw (J. A. Doornik, "An improved ziggurat
// method to generate normal random samples", 2005; the layout numpy uses). It is exact: the fast
// path (98.5 % of draws) accepts points of the rectangles that lie wholly under the density, the rest
// go through the exact wedge test or Marsaglia's exact tail method. The tables are exact up to the 12
// digits Marsaglia and Tsang give for the layer area v: the top layer closes to 1e-9 of v, an error
// of about 4e-12 in probability.
//
// Reproducible on every platform: only integer arithmetic and IEEE-754 basic operations (+ - * /,
// sqrt, floor, frexp, ldexp, all exactly rounded), so no std:: distribution (implementation defined)
// and no libm exp/log (not correctly rounded everywhere) in any value or decision: the two the ziggurat
// needs are written out below (the wedge test asks the platform's exp first, but only to settle the
// cases that are far from the boundary, so every decision is exp_neg's); the core is compiled with -ffp-contract=off
// (CMakeLists.txt), so no fused multiply-add changes a rounding either. The stream is sample-sequential with no buffer,
// so cutting a run into chunks of any size gives the same numbers.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "amb_fast/inline.hpp"
#include "amb_fast/lanes.hpp"

namespace amb_fast {

namespace random_detail {

constexpr double ln2_hi = 6.93147180369123816490e-01;  // ln 2 split so that k ln2_hi is exact
constexpr double ln2_lo = 1.90821492927058770002e-10;

// e^x for -708 < x <= 0 to about 1 ulp, from basic operations only: x = k ln 2 + r, |r| <= ln2 / 2,
// Taylor series of e^r to degree 13 (truncation below 4e-18 relative).
inline double exp_neg(double x) {
    const double k = std::floor(x * 1.4426950408889634 + 0.5);
    const double r = (x - k * ln2_hi) - k * ln2_lo;
    // clang-format off: a table
    constexpr double c[] = {1.0,           1.0,            1.0 / 2,         1.0 / 6,         1.0 / 24,
                            1.0 / 120,     1.0 / 720,      1.0 / 5040,      1.0 / 40320,     1.0 / 362880,
                            1.0 / 3628800, 1.0 / 39916800, 1.0 / 479001600, 1.0 / 6227020800};  // 1/n!
    // clang-format on
    double p = c[13];
    for (int n = 12; n >= 0; --n) p = p * r + c[n];
    return std::ldexp(p, static_cast<int>(k));
}

// ln x for 0 < x <= 1 (or any finite x > 0) to about 1 ulp: x = m 2^e with m in [sqrt(1/2), sqrt(2)),
// ln m = 2 atanh(s), s = (m - 1) / (m + 1), |s| < 0.172, series to s^23 (truncation below 1e-18).
inline double log_pos(double x) {
    int e = 0;
    double m = std::frexp(x, &e);  // m in [0.5, 1)
    if (m < 0.70710678118654752440) {
        m *= 2.0;
        --e;
    }
    const double s = (m - 1.0) / (m + 1.0), s2 = s * s;
    double p = 1.0 / 23.0;
    for (double n = 21.0; n >= 1.0; n -= 2.0) p = p * s2 + 1.0 / n;
    const double de = static_cast<double>(e);
    return de * ln2_hi + (2.0 * s * p + de * ln2_lo);
}

// The ziggurat's tables: layer i (1..255) spans |x| < x_i, every layer and the base (with the tail
// beyond r) of area v; computed once, from basic operations only, so identical everywhere.
struct Ziggurat {
    static constexpr double r = 3.6541528853610088;  // start of the tail
    static constexpr double v = 4.92867323399e-3;    // area of each layer
    static constexpr double m = 4503599627370496.0;  // 2^52: the abscissa's resolution
    std::array<std::uint64_t, 256> k{};              // accept at once if the 52-bit abscissa is below k[i]
    std::array<double, 256> w{};                     // x = abscissa * w[i]
    std::array<double, 256> f{};                     // density exp(-x_i^2 / 2) at the layer edges

    Ziggurat() {
        const double fr = exp_neg(-0.5 * r * r);
        const double q = v / fr;  // width of the base rectangle
        k[0] = static_cast<std::uint64_t>((r / q) * m);
        k[1] = 0;
        w[0] = q / m;
        w[255] = r / m;
        f[0] = 1.0;
        f[255] = fr;
        double outer = r;
        for (int i = 254; i >= 1; --i) {
            const double x = std::sqrt(-2.0 * log_pos(v / outer + exp_neg(-0.5 * outer * outer)));
            k[static_cast<std::size_t>(i) + 1] = static_cast<std::uint64_t>((x / outer) * m);
            outer = x;
            f[static_cast<std::size_t>(i)] = exp_neg(-0.5 * x * x);
            w[static_cast<std::size_t>(i)] = x / m;
        }
    }

    static const Ziggurat& tables() {
        static const Ziggurat z;
        return z;
    }
};

}  // namespace random_detail

// xoshiro256++: 256 bits of state, period 2^256 - 1, about 1 ns per 64-bit output.
class Xoshiro256pp {
  public:
    explicit Xoshiro256pp(std::uint64_t seed) {
        for (auto& word : s_) {  // splitmix64
            std::uint64_t z = (seed += 0x9e3779b97f4a7c15ULL);
            z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
            z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
            word = z ^ (z >> 31);
        }
    }

    AMB_FAST_ALWAYS_INLINE std::uint64_t operator()() {
        const std::uint64_t result = rotl(s_[0] + s_[3], 23) + s_[0];
        const std::uint64_t t = s_[1] << 17;
        s_[2] ^= s_[0];
        s_[3] ^= s_[1];
        s_[1] ^= s_[2];
        s_[0] ^= s_[3];
        s_[2] ^= t;
        s_[3] = rotl(s_[3], 45);
        return result;
    }

    // Uniform on [0, 1) with 53 random bits.
    double uniform() { return static_cast<double>((*this)() >> 11) * 0x1.0p-53; }
    // The 256-bit state, word by word (for generators advanced side by side: NormalLanes).
    const std::array<std::uint64_t, 4>& state() const { return s_; }
    void set_state(const std::array<std::uint64_t, 4>& s) { s_ = s; }

  private:
    static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    std::array<std::uint64_t, 4> s_{};
};

template <int K>
class NormalLanes;

// One noise source: independent N(0, sigma^2) deviates, one stream per seed. The numbers depend only
// on the seed and on how many were drawn before, never on how the draws are grouped into calls.
class NormalStream {
  public:
    explicit NormalStream(std::uint64_t seed) : rng_(seed), zig_(&random_detail::Ziggurat::tables()) {}

    // One standard normal deviate.
    AMB_FAST_ALWAYS_INLINE double operator()() {
        const std::uint64_t bits = rng_();
        double x;
        return in_rectangle(*zig_, bits, x) ? x : rare(bits);
    }

    // The stream drawn through a copy of its generator that a hot loop keeps in registers: the same
    // deviates in the same order (the rare path goes through the stream itself); commit() hands the
    // generator back, after which the stream continues where the copy stopped.
    class Local {
      public:
        explicit Local(NormalStream& stream) : stream_(&stream), rng_(stream.rng_), zig_(stream.zig_) {}
        AMB_FAST_ALWAYS_INLINE double operator()() {
            const std::uint64_t bits = rng_();
            double x;
            if (in_rectangle(*zig_, bits, x)) return x;
            stream_->rng_ = rng_;
            const double z = stream_->rare(bits);
            rng_ = stream_->rng_;
            return z;
        }
        void commit() { stream_->rng_ = rng_; }

      private:
        NormalStream* stream_;
        Xoshiro256pp rng_;
        const random_detail::Ziggurat* zig_;
    };

    // out[j * stride] = sigma * (next deviate), j < n.
    void fill(double* out, Eigen::Index n, double sigma, Eigen::Index stride = 1) {
        for (Eigen::Index j = 0; j < n; ++j) out[j * stride] = sigma * (*this)();
    }
    // out[j] += sigma * (next deviate), j < n.
    void add(double* out, Eigen::Index n, double sigma) {
        for (Eigen::Index j = 0; j < n; ++j) out[j] += sigma * (*this)();
    }

  private:
    template <int K>
    friend class NormalLanes;

    // The fast path (most draws): true, with the deviate in x, when the draw's point lies in its layer's
    // rectangle, wholly under the density. The layer is the low 8 bits, the abscissa the top 52.
    static AMB_FAST_ALWAYS_INLINE bool in_rectangle(const random_detail::Ziggurat& z, std::uint64_t bits, double& x) {
        const auto layer = static_cast<std::size_t>(bits & 0xff);
        const std::uint64_t abscissa = bits >> 12;  // 52 bits, disjoint from the layer's 8 and the sign bit
        if (abscissa >= z.k[layer]) return false;
        x = signed_by(abscissa_value(z, abscissa, layer), bits);
        return true;
    }

    // The sign comes from bit 8 of the draw, set without a branch (the fast path stays branch-free).
    static double signed_by(double x, std::uint64_t bits) {
        std::uint64_t u = 0;
        std::memcpy(&u, &x, sizeof u);
        u ^= (bits & 0x100) << 55;
        std::memcpy(&x, &u, sizeof u);
        return x;
    }
    static double abscissa_value(const random_detail::Ziggurat& z, std::uint64_t abscissa, std::size_t layer) {
        return static_cast<double>(static_cast<std::int64_t>(abscissa)) * z.w[layer];  // exact below 2^52
    }

    // Outside the rectangles (1.5 % of draws): the wedge test or the tail, else a fresh draw.
    double rare(std::uint64_t bits) {
        const auto& z = *zig_;
        for (;;) {
            const auto layer = static_cast<std::size_t>(bits & 0xff);
            const std::uint64_t abscissa = bits >> 12;
            const double x = abscissa_value(z, abscissa, layer);
            if (abscissa < z.k[layer]) return signed_by(x, bits);
            if (layer == 0) return signed_by(tail(), bits);
            // The wedge between the rectangle and the density: an exact test with a second uniform.
            if (below_density((z.f[layer - 1] - z.f[layer]) * rng_.uniform() + z.f[layer], x))
                return signed_by(x, bits);
            bits = rng_();
        }
    }

    // height < exp(-x^2 / 2) exactly as exp_neg decides it, at a fraction of its cost: the platform's
    // exp (within a few ulp wherever it comes from, 1e-12 is ten thousand times that) settles every
    // case except a height within 1e-12 of the density, which exp_neg decides. The wedge's |x| < r, so
    // nothing underflows.
    static bool below_density(double height, double x) {
        const double t = -0.5 * x * x, rough = std::exp(t);
        if (height < rough * (1.0 - 1e-12)) return true;
        if (height > rough * (1.0 + 1e-12)) return false;
        return height < random_detail::exp_neg(t);
    }

    // |x| beyond r, exactly (Marsaglia 1964): x = r + a with a ~ Exp(r) accepted with prob. exp(-a^2/2).
    double tail() {
        constexpr double r = random_detail::Ziggurat::r;
        for (;;) {
            const double a = -random_detail::log_pos(1.0 - rng_.uniform()) / r;  // 1 - u in (0, 1], exact
            const double b = -random_detail::log_pos(1.0 - rng_.uniform());
            if (b + b > a * a) return r + a;
        }
    }

    Xoshiro256pp rng_;
    const random_detail::Ziggurat* zig_;
};

#if AMB_FAST_LANES_OK
// K streams drawn side by side, one per SIMD lane: lane g's deviates are exactly those that its stream's
// operator() would give, in the same order (the generator's steps are integer operations, the fast
// path's arithmetic the same IEEE operations; a lane outside the rectangles takes its stream's own
// rare path). Sweeps draw their points' noise this way, four streams in one AVX2 register.
template <int K>
class NormalLanes {
  public:
    using Words = LaneWords<K>;
    using Values = Lanes<K>;

    // Lane g draws from streams[g] for g < count; the lanes after it from a scratch copy (discarded).
    NormalLanes(NormalStream* const* streams, int count) : spare_(*streams[0]) {
        for (int g = 0; g < K; ++g) {
            streams_[static_cast<std::size_t>(g)] = g < count ? streams[g] : &spare_;
            const auto& state = streams_[static_cast<std::size_t>(g)]->rng_.state();
            for (std::size_t w = 0; w < 4; ++w) words_[w][static_cast<std::size_t>(g)] = state[w];
        }
    }
    // The streams continue where their lanes stopped.
    void commit() {
        for (std::size_t g = 0; g < K; ++g) streams_[g]->rng_.set_state(lane_state(g));
    }

    // out[j K + g] = sigma * (lane g's next deviate), j < n.
    AMB_FAST_ALWAYS_INLINE void fill(double* out, Eigen::Index n, double sigma) {
        const random_detail::Ziggurat& z = random_detail::Ziggurat::tables();
        Words s0, s1, s2, s3;
        load(s0, s1, s2, s3);
        const Words magic = Words{} | 0x4330000000000000ULL;  // the exponent of 2^52
        for (Eigen::Index j = 0; j < n; ++j) {
            const Words bits = rotl(s0 + s3, 23) + s0;  // xoshiro256++, as Xoshiro256pp::operator()
            const Words t = s1 << 17;
            s2 ^= s0;
            s3 ^= s1;
            s1 ^= s2;
            s0 ^= s3;
            s2 ^= t;
            s3 = rotl(s3, 45);
            const Words abscissa = bits >> 12;
            Words bound;
            Values width;
            for (int g = 0; g < K; ++g) {
                const auto layer = static_cast<std::size_t>(bits[g] & 0xff);
                bound[g] = z.k[layer];
                width[g] = z.w[layer];
            }
            // abscissa < 2^52 as a double exactly (2^52 + a, less 2^52), times the layer's width,
            // signed by bit 8: NormalStream's fast path.
            const Values magnitude = (reinterpret<Values>(abscissa | magic) - 4503599627370496.0) * width;
            Values x = reinterpret<Values>(reinterpret<Words>(magnitude) ^ ((bits & 0x100) << 55));
            const auto inside = abscissa < bound;
            bool all_inside = true;
            for (int g = 0; g < K; ++g) all_inside = all_inside && inside[g];
            if (!all_inside) {  // a lane outside the rectangles: its stream's rare path
                store(s0, s1, s2, s3);
                for (std::size_t g = 0; g < K; ++g) {
                    if (inside[g]) continue;
                    NormalStream& stream = *streams_[g];
                    stream.rng_.set_state(lane_state(g));
                    x[g] = stream.rare(bits[g]);
                    const auto& state = stream.rng_.state();
                    for (std::size_t w = 0; w < 4; ++w) words_[w][g] = state[w];
                }
                load(s0, s1, s2, s3);
            }
            const Values deviate = sigma * x;
            std::memcpy(out + j * K, &deviate, sizeof deviate);
        }
        store(s0, s1, s2, s3);
    }

  private:
    static AMB_FAST_ALWAYS_INLINE Words rotl(Words x, int k) { return (x << k) | (x >> (64 - k)); }
    template <class To, class From>
    static AMB_FAST_ALWAYS_INLINE To reinterpret(From v) {
        static_assert(sizeof(To) == sizeof(From));
        To out;
        std::memcpy(&out, &v, sizeof out);
        return out;
    }
    // Through memcpy: this object may sit at an address the AVX2 kernel's aligned loads would fault on.
    AMB_FAST_ALWAYS_INLINE void load(Words& s0, Words& s1, Words& s2, Words& s3) const {
        std::memcpy(&s0, words_[0].data(), sizeof s0);
        std::memcpy(&s1, words_[1].data(), sizeof s1);
        std::memcpy(&s2, words_[2].data(), sizeof s2);
        std::memcpy(&s3, words_[3].data(), sizeof s3);
    }
    AMB_FAST_ALWAYS_INLINE void store(const Words& s0, const Words& s1, const Words& s2, const Words& s3) {
        std::memcpy(words_[0].data(), &s0, sizeof s0);
        std::memcpy(words_[1].data(), &s1, sizeof s1);
        std::memcpy(words_[2].data(), &s2, sizeof s2);
        std::memcpy(words_[3].data(), &s3, sizeof s3);
    }
    std::array<std::uint64_t, 4> lane_state(std::size_t g) const {
        return {words_[0][g], words_[1][g], words_[2][g], words_[3][g]};
    }

    std::array<std::array<std::uint64_t, K>, 4> words_{};  // words_[w][g]: word w of lane g's state
    std::array<NormalStream*, K> streams_{};
    NormalStream spare_;
};
#endif

}  // namespace amb_fast
