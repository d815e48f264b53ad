#include "amb_fast/mimo_lines.hpp"

#include <Eigen/Eigenvalues>  // HessenbergDecomposition
#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <numeric>
#include <stdexcept>

#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
#include "amb_fast/random.hpp"
#include "amb_fast/spectrum.hpp"
#include "amb_fast/steady.hpp"

namespace amb_fast {

using cd = std::complex<double>;

namespace {
constexpr double pi = 3.14159265358979323846;

// From rest: the loop sample by sample, every recorded period transformed.
void lines_from_rest(const MimoModel& model, const double* const* period_force, Eigen::Index L,
                     Eigen::Index settle_periods, Eigen::Index periods, const std::vector<std::uint64_t>& seeds,
                     const std::vector<Eigen::Index>& bins, cd* force_lines, cd* displacement_lines) {
    const auto K = static_cast<Eigen::Index>(seeds.size());
    const Eigen::Index p = model.forces(), q = model.probes(), r = model.outputs();
    const auto B = static_cast<Eigen::Index>(bins.size());
    MimoLoop loop(model, seeds);
    LineTransform transform(L, bins, LineTransform::Method::fft);
    std::vector<Eigen::MatrixXd> rec(static_cast<std::size_t>(K), Eigen::MatrixXd(p, L)),
        out(static_cast<std::size_t>(K), Eigen::MatrixXd(r, L));  // column k = sample k
    std::vector<double*> rec_ptr, out_ptr;
    for (Eigen::Index l = 0; l < K; ++l) {
        rec_ptr.push_back(rec[static_cast<std::size_t>(l)].data());
        out_ptr.push_back(out[static_cast<std::size_t>(l)].data());
    }
    Eigen::VectorXd row(L), row2(L);
    std::vector<cd> spectrum(static_cast<std::size_t>(B)), spectrum2(spectrum.size());
    // lines[((period * B + j) * channels + channel) * K + l] = spectrum[j]
    auto put = [&](cd* lines, Eigen::Index period, Eigen::Index channels, Eigen::Index channel, Eigen::Index l) {
        for (Eigen::Index j = 0; j < B; ++j)
            lines[((period * B + j) * channels + channel) * K + l] = spectrum[static_cast<std::size_t>(j)];
    };
    for (Eigen::Index k = 0; k < settle_periods + periods; ++k) {
        loop.run(period_force, L, rec_ptr.data(), out_ptr.data());
        if (k < settle_periods) continue;
        const Eigen::Index period = k - settle_periods;
        for (Eigen::Index l = 0; l < K; ++l) {
            Eigen::Index c = 0;
            for (; c + 2 <= q; c += 2) {  // two probes at once: the same digits, side by side in SIMD lanes
                row = out[static_cast<std::size_t>(l)].row(c).transpose();
                row2 = out[static_cast<std::size_t>(l)].row(c + 1).transpose();
                transform(row.data(), row2.data(), spectrum.data(), spectrum2.data());
                put(displacement_lines, period, q, c, l);
                spectrum.swap(spectrum2);
                put(displacement_lines, period, q, c + 1, l);
            }
            for (; c < q; ++c) {
                row = out[static_cast<std::size_t>(l)].row(c).transpose();
                transform(row.data(), spectrum.data());
                put(displacement_lines, period, q, c, l);
            }
            for (c = 0; c < p; ++c) {
                row = rec[static_cast<std::size_t>(l)].row(c).transpose();
                transform(row.data(), spectrum.data());
                put(force_lines, period, p, c, l);
            }
        }
    }
}

}  // namespace

// Per line, with z = e^{jw} and M = T H T^-1 (H upper Hessenberg): what the forces and the probe noise
// give at the probes (G), what the noise's spectrum gives the state at the period's end (through Xn),
// and what a state change over the period gives at the probes (CRz).
LineSolves::LineSolves(const MimoModel& model_in, Eigen::Index L_in, std::vector<Eigen::Index> bins_in)
    : model(validated(model_in)), L(L_in), bins(std::move(bins_in)) {
    const Eigen::Index n = model.states(), p = model.forces(), q = model.probes(), m = p + q;
    const auto B = static_cast<Eigen::Index>(bins.size());
    for (const Eigen::Index bin : bins)
        require(bin > 0 && 2 * bin < L, "bin", bin, "strictly between 0 and half the period (steady start)");
    // M = T H T^-1 with T = D Q: D balances, Q is the orthogonal Hessenberg reduction of D^-1 M D.
    const Eigen::VectorXd scale = balancing(model.M);
    const Eigen::MatrixXd balanced = scale.cwiseInverse().asDiagonal() * model.M * scale.asDiagonal();
    const Eigen::HessenbergDecomposition<Eigen::MatrixXd> hessenberg(balanced);
    const Eigen::MatrixXd H = hessenberg.matrixH(), Q = hessenberg.matrixQ();
    const Eigen::MatrixXd T = scale.asDiagonal() * Q;
    T_inverse = Q.transpose() * scale.cwiseInverse().asDiagonal();
    Eigen::MatrixXd inputs(n, m);
    inputs << model.Bf, model.Bn;
    const Eigen::MatrixXd Bt = T_inverse * inputs, Ct = model.C.topRows(q) * T;
    const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
    ML = matrix_power(model.M, L);
    const Eigen::MatrixXd W = (I - ML) * T;  // the state change over a period, from Hessenberg coordinates
    // Per line k: G = Ct (zI - H)^-1 T^-1 [Bf Bn] + [0 Dn], the probes' response to the forces (p columns)
    // and to the noise (q), from the rows of C (zI - M)^-1 T = Ct (zI - H)^-1 (transposed solves); kept
    // times z, real and imaginary parts apart (CRz), for the state's change over a period. And
    // Xn = (zI - H)^-1 T^-1 Bn, the state's response to the noise (Hessenberg coordinates), as real
    // columns (Re, -Im) per probe, so that Re(Xn V) is one real product with V as (Re, Im) pairs.
    G.resize(q, B * m);
    CRz_re.resize(B * q, n);
    CRz_im.resize(B * q, n);
    Xn.resize(n, 2 * B * q);
    z.resize(static_cast<std::size_t>(B));
    for (Eigen::Index k = 0; k < B; ++k)
        z[static_cast<std::size_t>(k)] =
            std::polar(1.0, 2.0 * pi * static_cast<double>(bins[static_cast<std::size_t>(k)]) / static_cast<double>(L));
    // Four lines at a time (the last group padded with its last line), each lane's solutions copied out.
    // Bt and Ct are real, so G's entries are sums of real times complex, summed in the lanes.
    constexpr int lanes = HessenbergLU::lanes;
    HessenbergLU lu(H);
    std::vector<double> re(static_cast<std::size_t>(n * lanes)), im(re.size());
    const auto at = [](Eigen::Index i, int l) { return static_cast<std::size_t>(i * lanes + l); };
    const auto load = [&](const auto& b) {  // the same real right-hand side in every lane
        for (Eigen::Index i = 0; i < n; ++i)
            for (int l = 0; l < lanes; ++l) re[at(i, l)] = b[i], im[at(i, l)] = 0.0;
    };
    for (Eigen::Index k0 = 0; k0 < B; k0 += lanes) {
        if (k0 % 64 == 0) poll_interrupt();
        const Eigen::Index count = std::min<Eigen::Index>(lanes, B - k0);
        cd shifts[lanes];
        for (int l = 0; l < lanes; ++l)
            shifts[l] = z[static_cast<std::size_t>(k0 + std::min<Eigen::Index>(l, count - 1))];
        lu.factor(shifts);
        for (Eigen::Index j = 0; j < q; ++j) {
            load(Bt.col(p + j));
            lu.solve(re.data(), im.data());
            for (Eigen::Index l = 0; l < count; ++l)
                for (Eigen::Index i = 0; i < n; ++i) {
                    Xn(i, 2 * ((k0 + l) * q + j)) = re[at(i, static_cast<int>(l))];
                    Xn(i, 2 * ((k0 + l) * q + j) + 1) = -im[at(i, static_cast<int>(l))];
                }
        }
        for (Eigen::Index i = 0; i < q; ++i) {
            load(Ct.row(i));
            lu.solve_transposed(re.data(), im.data());  // row i of C (zI - M)^-1 T, per lane
            for (Eigen::Index c = 0; c < m; ++c) {      // G(i, c) = that row times column c of Bt
                double g_re[lanes] = {}, g_im[lanes] = {};
                for (Eigen::Index s = 0; s < n; ++s)
                    for (int l = 0; l < lanes; ++l)
                        g_re[l] += re[at(s, l)] * Bt(s, c), g_im[l] += im[at(s, l)] * Bt(s, c);
                const double direct = c >= p ? model.Dn(i, c - p) : 0.0;
                for (Eigen::Index l = 0; l < count; ++l) G(i, (k0 + l) * m + c) = cd(g_re[l] + direct, g_im[l]);
            }
            for (Eigen::Index l = 0; l < count; ++l) {
                const cd zk = z[static_cast<std::size_t>(k0 + l)];
                for (Eigen::Index s = 0; s < n; ++s) {
                    const cd r = zk * cd(re[at(s, static_cast<int>(l))], im[at(s, static_cast<int>(l))]);
                    CRz_re((k0 + l) * q + i, s) = r.real();
                    CRz_im((k0 + l) * q + i, s) = r.imag();
                }
            }
        }
    }
    // The noise's state: stationary covariance P; over a period w = zL - M^L z0 has covariance
    // P - M^L P M^LT, of which the lines' spectra explain (2 / L) sum sigma^2 Re(S S^H), S = W Xn.
    const Eigen::MatrixXd P = stationary_noise_covariance(model);
    root = covariance_root(P);
    Eigen::VectorXd root_explained(2 * B * q);  // per column of Xn: sqrt((2 / L) sigma^2) of its probe
    for (Eigen::Index k = 0; k < B; ++k)
        for (Eigen::Index j = 0; j < q; ++j)
            root_explained.segment(2 * (k * q + j), 2)
                .setConstant(std::sqrt(2.0 / static_cast<double>(L)) * model.sensor_noise[j]);
    Eigen::MatrixXd explained_by_lines = Eigen::MatrixXd::Zero(n, n);  // Xn diag(explained) Xn^T, one triangle
    explained_by_lines.selfadjointView<Eigen::Lower>().rankUpdate(Xn * root_explained.asDiagonal());
    explained_by_lines = explained_by_lines.selfadjointView<Eigen::Lower>();
    Eigen::MatrixXd residual = P - ML * P * ML.transpose() - W * explained_by_lines * W.transpose();
    residual_root = covariance_root(0.5 * (residual + residual.transpose()));
    WL = (2.0 / static_cast<double>(L)) * W;
}

std::size_t LineSolves::bytes() const {
    std::size_t doubles = 0;
    for (const Eigen::MatrixXd* x : {&T_inverse, &ML, &WL, &residual_root, &CRz_re, &CRz_im, &Xn, &root})
        doubles += static_cast<std::size_t>(x->size());
    return 8 * (doubles + 2 * static_cast<std::size_t>(G.size() + model.M.size()));
}

std::shared_ptr<const LineSolves> LineSolves::shared(const MimoModel& model, Eigen::Index L,
                                                     const std::vector<Eigen::Index>& bins) {
    const auto same = [](const auto& a, const auto& b) {  // bitwise: shapes and every double
        return a.rows() == b.rows() && a.cols() == b.cols() &&
               std::memcmp(a.data(), b.data(), static_cast<std::size_t>(a.size()) * sizeof(double)) == 0;
    };
    const auto matches = [&](const LineSolves& solved) {
        const MimoModel& m = solved.model;
        return solved.L == L && solved.bins == bins && same(m.M, model.M) && same(m.Bf, model.Bf) &&
               same(m.Bn, model.Bn) && same(m.C, model.C) && same(m.Dn, model.Dn) &&
               same(m.transducer_pole, model.transducer_pole) && same(m.sensor_noise, model.sensor_noise) &&
               same(m.force_noise, model.force_noise);
    };
    // The last few (up to 32 MB together), any thread's; made outside the lock.
    static std::mutex guard;
    static std::vector<std::shared_ptr<const LineSolves>> recent;
    {
        const std::lock_guard<std::mutex> lock(guard);
        for (const auto& solved : recent)
            if (matches(*solved)) return solved;
    }
    auto solved = std::make_shared<const LineSolves>(model, L, bins);
    constexpr std::size_t budget = std::size_t{32} << 20;
    if (solved->bytes() > budget) return solved;
    const std::lock_guard<std::mutex> lock(guard);
    recent.push_back(solved);
    std::size_t total = 0;
    for (const auto& kept : recent) total += kept->bytes();
    while (recent.size() > 4 || total > budget) {
        total -= recent.front()->bytes();
        recent.erase(recent.begin());
    }
    return solved;
}

SteadyLines::SteadyLines(const MimoModel& model, Eigen::Index L, std::vector<Eigen::Index> bins, NoiseSources sources)
    : SteadyLines(std::make_shared<const LineSolves>(model, L, std::move(bins)), std::move(sources)) {}

SteadyLines::SteadyLines(std::shared_ptr<const LineSolves> solves, NoiseSources sources)
    : solves_(std::move(solves)), sources_(std::move(sources)) {
    const Eigen::Index p = solves_->model.forces(), q = solves_->model.probes();
    for (auto [ids, count] : {std::pair{&sources_.probes, q}, std::pair{&sources_.forces, p}}) {
        if (ids->empty())
            for (Eigen::Index j = 0; j < count; ++j) ids->push_back(j);
        require(static_cast<Eigen::Index>(ids->size()) == count, "noise sources", ids->size(), "one per channel");
    }
    clean_force_.resize(static_cast<Eigen::Index>(solves_->bins.size()), p);
    det_.resize(static_cast<Eigen::Index>(solves_->bins.size()) * q);
}

void SteadyLines::start(const double* period_force, std::uint64_t seed, Eigen::Index periods) {
    const LineSolves& s = *solves_;
    const Eigen::Index p = s.model.forces(), q = s.model.probes(), m = p + q;
    const auto B = static_cast<Eigen::Index>(s.bins.size());
    // The forces' lines, the probes' periodic response to them, the recorded (transduced) force lines.
    // The last few channels transformed (on any thread), kept: a sweep's points, repeated experiments and
    // the two-axis pair (s and -s) share their excitations, and comparing one costs a twentieth of its
    // transform.
    struct Transformed {
        std::vector<double> samples;
        std::vector<Eigen::Index> bins;
        std::vector<cd> lines;
    };
    static std::mutex guard;
    static std::vector<Transformed> recent;
    std::vector<double> channel(static_cast<std::size_t>(s.L));
    std::vector<cd> spectrum(static_cast<std::size_t>(B));
    Eigen::MatrixXcd F(B, p);
    for (Eigen::Index c = 0; c < p; ++c) {
        for (Eigen::Index k = 0; k < s.L; ++k) channel[static_cast<std::size_t>(k)] = period_force[k * p + c];
        bool found = false;
        {
            const std::lock_guard<std::mutex> lock(guard);
            for (const Transformed& t : recent)  // bitwise the same samples: their transform
                if (t.bins == s.bins && t.samples.size() == channel.size() &&
                    std::memcmp(channel.data(), t.samples.data(), channel.size() * sizeof(double)) == 0) {
                    spectrum = t.lines;
                    found = true;
                    break;
                }
        }
        if (!found) {
            if (!transform_) transform_.emplace(s.L, s.bins, LineTransform::Method::automatic);
            (*transform_)(channel.data(), spectrum.data());
            const std::lock_guard<std::mutex> lock(guard);
            if (recent.size() == 4) recent.erase(recent.begin());
            recent.push_back({channel, s.bins, spectrum});
        }
        const double a = s.model.transducer_pole[c];
        for (Eigen::Index k = 0; k < B; ++k) {
            const cd zk = s.z[static_cast<std::size_t>(k)];
            F(k, c) = spectrum[static_cast<std::size_t>(k)];
            clean_force_(k, c) = a > 0.0 ? F(k, c) * (zk - 1.0) / (zk - a) : F(k, c);
        }
    }
    for (Eigen::Index k = 0; k < B; ++k)
        det_.segment(k * q, q) = s.G.middleCols(k * m, p).lazyProduct(F.row(k).transpose());
    // The noise: the state starts in its stationary distribution, then goes on period by period.
    rest_.emplace(stream_seed(seed, 3, sources_.part));
    probe_.clear();
    for (Eigen::Index j = 0; j < q; ++j)
        probe_.emplace_back(stream_seed(seed, 0, sources_.probes[static_cast<std::size_t>(j)]));
    force_.clear();
    for (Eigen::Index c = 0; c < p; ++c)
        force_.emplace_back(stream_seed(seed, 2, sources_.forces[static_cast<std::size_t>(c)]));
    Eigen::VectorXd z0 = Eigen::VectorXd::Zero(s.model.states());
    add_stationary_noise(s.root, sources_.part == 0 ? seed : stream_seed(seed, 4, sources_.part), z0);
    Z_.resize(s.model.states(), std::min(periods, block) + 1);
    Z_.col(0) = z0;
    left_ = periods;
    drawn_ = next_ = 0;
}

// The next block's periods: their noise spectra (each stream in period order), the states at their ends
// (z' = M^L z + W (2 / L) Re(Xn V) + the residual), and what each period's change of state leaks into
// the lines.
void SteadyLines::draw_block() {
    const LineSolves& s = *solves_;
    poll_interrupt();
    if (left_ <= 0) throw std::logic_error("SteadyLines::next: more periods than start() was told");
    const Eigen::Index q = s.model.probes(), n = s.model.states();
    const auto B = static_cast<Eigen::Index>(s.bins.size());
    // Up to `block` periods, fewer where their noise spectra would pass a megabyte (very many lines).
    const Eigen::Index P = std::min({left_, block, std::max<Eigen::Index>(1, (Eigen::Index{1} << 17) / (2 * B * q))});
    Z_.col(0) = Z_.col(drawn_);  // the last block's end
    V_.resize(2 * B * q, P);
    draws_.resize(n, P);
    for (Eigen::Index period = 0; period < P; ++period) {
        for (Eigen::Index j = 0; j < q; ++j) {  // V: (Re, Im) per line and probe
            const double sigma = std::sqrt(0.5 * static_cast<double>(s.L)) * s.model.sensor_noise[j];
            NormalStream::Local draw(probe_[static_cast<std::size_t>(j)]);
            for (Eigen::Index k = 0; k < B; ++k) {
                double re = 0.0, im = 0.0;
                if (sigma > 0.0) re = draw(), im = draw();
                V_(2 * (k * q + j), period) = sigma * re;
                V_(2 * (k * q + j) + 1, period) = sigma * im;
            }
            draw.commit();
        }
        rest_->fill(draws_.col(period).data(), n, 1.0);
    }
    Eigen::MatrixXd w = s.WL * (s.Xn * V_);  // n x P
    w.noalias() += s.residual_root * draws_;
    for (Eigen::Index period = 0; period < P; ++period)
        Z_.col(period + 1).noalias() = s.ML * Z_.col(period) + w.col(period);
    const Eigen::MatrixXd d = s.T_inverse * (Z_.middleCols(1, P) - Z_.leftCols(P));
    change_re_.noalias() = s.CRz_re * d;
    change_im_.noalias() = s.CRz_im * d;
    left_ -= P;
    drawn_ = P;
    next_ = 0;
}

void SteadyLines::next(cd* force_lines, cd* displacement_lines, const LineLayout& force_layout,
                       const LineLayout& displacement_layout) {
    if (next_ == drawn_) draw_block();
    const LineSolves& s = *solves_;
    const Eigen::Index period = next_++;
    const Eigen::Index p = s.model.forces(), q = s.model.probes(), m = p + q;
    const auto B = static_cast<Eigen::Index>(s.bins.size());
    const auto v = V_.col(period);
    double zero_if_finite = 0.0;  // 0 y is 0 for a finite y, NaN for an infinite or NaN one
    for (Eigen::Index k = 0; k < B; ++k)
        for (Eigen::Index i = 0; i < q; ++i) {
            cd y = det_[k * q + i] - cd(change_re_(k * q + i, period), change_im_(k * q + i, period));
            for (Eigen::Index j = 0; j < q; ++j)
                y += s.G(i, k * m + p + j) * cd(v[2 * (k * q + j)], v[2 * (k * q + j) + 1]);
            zero_if_finite += 0.0 * y.real() + 0.0 * y.imag();
            displacement_lines[displacement_layout.at(k, i, q)] = y;
        }
    if (zero_if_finite != 0.0) throw std::overflow_error("the line spectra became non-finite: the loop is unstable");
    // The force transducers' white noise: N(0, L sigma^2 / 2) in the real and in the imaginary part of
    // every line, one stream per channel, line by line.
    for (Eigen::Index c = 0; c < p; ++c) {
        const double sigma = std::sqrt(0.5 * static_cast<double>(s.L)) * s.model.force_noise[c];
        NormalStream::Local draw(force_[static_cast<std::size_t>(c)]);
        for (Eigen::Index k = 0; k < B; ++k) {
            cd value = clean_force_(k, c);
            if (sigma > 0.0) {
                const double re = draw(), im = draw();
                value += cd(sigma * re, sigma * im);
            }
            force_lines[force_layout.at(k, c, p)] = value;
        }
        draw.commit();
    }
}

namespace {
// From the periodic steady state, the line spectra drawn period by period (SteadyLines), the experiments
// in lock step (their lines side by side in the output), all drawing from one LineSolves. A model of
// independent parts (an uncoupled two-axis rig) is drawn part by part: each part's solves and products are
// those of its own size, and parts bitwise alike are solved once.
void steady_lines(const MimoModel& model, const double* const* period_force, Eigen::Index L, Eigen::Index periods,
                  const std::vector<std::uint64_t>& seeds, const std::vector<Eigen::Index>& bins, cd* force_lines,
                  cd* displacement_lines) {
    const auto K = static_cast<Eigen::Index>(seeds.size());
    const Eigen::Index p = model.forces(), q = model.probes();
    const auto B = static_cast<Eigen::Index>(bins.size());
    std::vector<MimoPart> parts = independent_parts(model);
    if (std::any_of(parts.begin(), parts.end(),
                    [](const MimoPart& part) { return part.forces.empty() || part.probes.empty(); })) {
        const auto all = [](Eigen::Index count) {  // a part no force drives or no probe sees: drawn whole
            std::vector<Eigen::Index> ids(static_cast<std::size_t>(count));
            std::iota(ids.begin(), ids.end(), Eigen::Index{0});
            return ids;
        };
        parts = {MimoPart{all(model.states()), all(p), all(q)}};
    }
    for (std::size_t t = 0; t < parts.size(); ++t) {
        const std::vector<Eigen::Index>& forces = parts[t].forces;
        const std::vector<Eigen::Index>& probes = parts[t].probes;
        const auto pp = static_cast<Eigen::Index>(forces.size());
        const auto solves = LineSolves::shared(parts.size() == 1 ? model : parts[t].model(model), L, bins);
        std::vector<SteadyLines> draws;
        draws.reserve(static_cast<std::size_t>(K));
        std::vector<double> force(parts.size() > 1 ? static_cast<std::size_t>(L * pp) : 0);
        for (Eigen::Index l = 0; l < K; ++l) {
            for (Eigen::Index k = 0; parts.size() > 1 && k < L; ++k)  // one part: every force channel, in order
                for (Eigen::Index c = 0; c < pp; ++c)
                    force[static_cast<std::size_t>(k * pp + c)] =
                        period_force[l][k * p + forces[static_cast<std::size_t>(c)]];
            draws.emplace_back(solves, NoiseSources{probes, forces, static_cast<Eigen::Index>(t)});
            draws.back().start(parts.size() > 1 ? force.data() : period_force[l], seeds[static_cast<std::size_t>(l)],
                               periods);
        }
        // Line k, channel c of experiment l's period at ((period * B + k) * channels + channel) * K + l.
        const LineLayout force_layout{p * K, K, forces.data()}, displacement_layout{q * K, K, probes.data()};
        for (Eigen::Index period = 0; period < periods; ++period)
            for (Eigen::Index l = 0; l < K; ++l)
                draws[static_cast<std::size_t>(l)].next(force_lines + period * B * p * K + l,
                                                        displacement_lines + period * B * q * K + l, force_layout,
                                                        displacement_layout);
    }
}
}  // namespace

void mimo_line_experiments(const MimoModel& model, const double* const* period_force, Eigen::Index L,
                           Eigen::Index settle_periods, Eigen::Index periods, const std::vector<std::uint64_t>& seeds,
                           bool steady_start, const std::vector<Eigen::Index>& bins, cd* force_lines,
                           cd* displacement_lines) {
    require(L > 0, "period", L, "> 0 samples");
    require(settle_periods >= 0, "settle_periods", settle_periods, ">= 0");
    require(periods >= 2, "periods", periods, ">= 2 (standard errors need at least two)");
    model.validate();
    const auto K = static_cast<Eigen::Index>(seeds.size());
    for (Eigen::Index l = 0; l < K; ++l) require_finite_samples("excitation", period_force[l], L * model.forces());
    if (!steady_start) {
        lines_from_rest(model, period_force, L, settle_periods, periods, seeds, bins, force_lines, displacement_lines);
        return;
    }
    steady_lines(model, period_force, L, periods, seeds, bins, force_lines, displacement_lines);
}

}  // namespace amb_fast
