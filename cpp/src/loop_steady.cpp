// The loop as a linear map: its state stacked as z (steady.hpp), the start in the periodic steady
// state, and the linear(ised) loop as a MimoModel.
#include "amb_fast/loop.hpp"

#include "amb_fast/steady.hpp"

namespace amb_fast {

Eigen::VectorXd Loop::stacked_state() const {
    const Controller& c = controller_.controller();
    const int n = c.order(), d = c.delay;
    const bool fractional = fraction_ > 0.0;
    Eigen::VectorXd z(state::size + n + d + int(fractional));
    z.head<state::size>() = x_;
    if (fractional) z[z.size() - 1] = u_prev_;
    for (int j = 0; j < n; ++j) z[state::size + j] = controller_.state()[j];
    for (int j = 0; j < d; ++j) z[state::size + n + j] = controller_.line(j);
    return z;
}

void Loop::set_stacked_state(const Eigen::VectorXd& z) {
    const Controller& c = controller_.controller();
    const int n = c.order(), d = c.delay;
    x_ = z.head<state::size>();
    if (fraction_ > 0.0) u_prev_ = z[z.size() - 1];
    for (int j = 0; j < n; ++j) controller_.state()[j] = z[state::size + j];
    for (int j = 0; j < d; ++j) controller_.set_line(j, z[state::size + n + j]);
}

void Loop::start_periodic(const double* period_force, Eigen::Index L) {
    Loop probe = periodic_probe();
    Eigen::VectorXd f(L), y(L), i(L);
    probe.run(period_force, L, {f.data(), y.data(), i.data()});
    start_periodic_from(probe, L);
}

Loop Loop::periodic_probe() const {
    // The noise-free linear loop without limits, run by the same kernel.
    Rig quiet = rig_;
    quiet.force_law = ForceLaw::linear;
    quiet.sensor_noise = quiet.force_noise = 0.0;
    quiet.clearance.reset();
    quiet.current_limit.reset();
    Controller own = controller_.controller();  // the dead time's whole samples are in its delay already
    own.delay -= split_dead_time(rig_.dead_time, T_).samples;
    return Loop(quiet, own);
}

void Loop::start_periodic_from(const Loop& probe, Eigen::Index L) {
    const ClosedLoopMap map(plant_ ? *plant_ : sample_map(probe.rig_, T_), sensed_, controller_.controller(),
                            fraction_);
    Eigen::VectorXd z = periodic_start(map.M, L, probe.stacked_state());
    if (rig_.sensor_noise > 0.0) {
        NormalStream draws(start_noise_seed(seed_));
        Eigen::VectorXd w(z.size());
        draws.fill(w.data(), w.size(), 1.0);
        z += covariance_root(
                 stationary_covariance(map.M, map.noise_in, Eigen::VectorXd::Constant(1, rig_.sensor_noise))) *
             w;
    }
    set_stacked_state(z);
    transducer_.set_state(periodic_transducer_start(transducer_.pole(), L, probe.transducer_.state()));
}

MimoModel Loop::linear_model() const {
    Rig linear = rig_;
    linear.force_law = ForceLaw::linear;
    const SampleMap plant = plant_ ? *plant_ : sample_map(linear, T_);
    const ClosedLoopMap map(plant, sensed_, controller_.controller(), fraction_);
    const Eigen::Index n = map.M.rows();
    MimoModel model;
    model.M = map.M;
    model.Bf = Eigen::MatrixXd::Zero(n, 1);
    model.Bf.topRows(state::size) = plant.Gf;
    model.Bn = map.noise_in;
    model.C = Eigen::MatrixXd::Zero(1, n);
    model.C(0, sensed_) = 1.0;
    model.Dn = Eigen::MatrixXd::Ones(1, 1);
    model.transducer_pole = Eigen::VectorXd::Constant(1, transducer_.pole());
    model.sensor_noise = Eigen::VectorXd::Constant(1, rig_.sensor_noise);
    model.force_noise = Eigen::VectorXd::Constant(1, rig_.force_noise);
    return model;
}

}  // namespace amb_fast
