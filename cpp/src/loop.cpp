// The loop's construction (the controller's delay lengthened by the rig's dead time), its report of
// a failure, and simulate().
#include "amb_fast/loop.hpp"

#include <sstream>
#include <stdexcept>

#include "amb_fast/errors.hpp"

namespace amb_fast {

namespace {
// The controller as the loop runs it: its own delay plus the rig's dead time in whole samples.
Controller with_dead_samples(const Controller& controller, const Rig& rig) {
    Controller c = validated(controller);
    c.delay += split_dead_time(validated(rig).dead_time, c.period()).samples;
    return c;
}
}  // namespace

Loop::Loop(const Rig& rig, const Controller& controller, std::uint64_t seed)
    : rig_(validated(rig)),
      controller_(with_dead_samples(controller, rig)),
      T_(controller.period()),
      sensed_(rig.sensor_bandwidth ? state::ys : state::y),
      has_amp_(rig.amp_bandwidth.has_value()),
      drive_(force_current_index(rig)),
      magnets_(rig),
      limit_(rig.command_limit()),
      touchdown_(rig.touchdown_at()),
      seed_(seed),
      sensor_rng_(seed),
      force_rng_(seed ^ 0x9e3779b97f4a7c15ULL),
      transducer_(rig, controller.period()) {
    fraction_ = split_dead_time(rig_.dead_time, T_).fraction;
    if (rig_.force_law == ForceLaw::linear) {
        plant_.emplace(sample_map(rig_, T_));
        map_.emplace(*plant_);
    } else {
        auto stretch = [&](double length) {
            const double h = length / rig_.substeps;
            return Stretch{h, propagator(rig_, h), propagator(rig_, h / 2)};
        };
        if (fraction_ > 0.0) early_ = stretch(fraction_);
        late_ = stretch(T_ - fraction_);
    }
}

void Loop::fail(Eigen::Index sample, const char* what) const {
    std::ostringstream msg;
    msg << what << " (at sample " << sample << ", t = " << sample * T_ << " s)";
    throw std::overflow_error(msg.str());
}

void simulate(const Rig& rig, const Controller& controller, const double* force, Eigen::Index n, Channels out,
              std::uint64_t seed) {
    require_finite_samples("force", force, n);
    Loop loop(rig, controller, seed);
    loop.run(force, n, out);
}

}  // namespace amb_fast
