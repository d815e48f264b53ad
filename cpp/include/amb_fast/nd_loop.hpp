// The linear sampled-data loop of N controlled axes (python/amb_fast/system/_model.py): the structure's
// matrices joined with each axis' chain of the one-axis rig, discretised exactly with each axis' dead
// time, closed with the controller matrix's state space. One assembler for 1, 2 and 4 axes.
#pragma once

#include <Eigen/Dense>
#include <vector>

namespace amb_fast {

// M q'' + (C + speed G) q' + K q = A^T f over n coordinates, N axes (Mechanics, SI).
struct NdStructure {
    Eigen::MatrixXd mass, gyroscopic, stiffness, damping;  // n x n
    Eigen::MatrixXd actuators, probes;                     // N x n
    double speed = 0.0;                                    // rad/s
};

// Each axis' chain, one entry per axis; NaN bandwidth: an ideal stage, NaN force_coupling_tau: DC.
struct NdChains {
    Eigen::VectorXd kyy, kiy;                                         // N/m, N/A
    Eigen::VectorXd amp_bandwidth, eddy_bandwidth, sensor_bandwidth;  // Hz
    Eigen::VectorXd mass_loading, dead_time, force_coupling_tau;      // kg, s, s
};

// The controller matrix from the N probes' e[k] (m) to the N current commands (A).
struct NdController {
    Eigen::MatrixXd A, B, C, D;
};

// What is assembled: the continuous plant always, the discrete plant with fs > 0, the loop with a
// controller. Indices into the plant's states; -1 where a stage is ideal.
struct NdLoop {
    std::vector<int> position, velocity;  // per coordinate
    std::vector<int> coil, eddy, sensor;  // per axis: i, i_f, ys
    std::vector<int> lines;               // per axis: its command line's length (dead1 ..)
    Eigen::MatrixXd A, B, S;              // continuous A, B (inputs: N forces, N commands); S: probe rows
    Eigen::MatrixXd Phi, Gamma;           // one sample, command lines appended per axis
    Eigen::MatrixXd M, Bf, Bn, C, Dn;     // closed loop; outputs the N probe readings, then N coil currents
    Eigen::VectorXd poles;                // per axis: the force transducer's AC-coupling pole (0: DC)
};

// Throws std::invalid_argument naming a bad parameter (shapes, non-finite, singular mass).
NdLoop nd_loop(const NdStructure& structure, const NdChains& chains, double fs, const NdController* controller);

// nd_loop for every point, the points claimed in turn by `workers` threads (<= 0: one per core).
struct NdPoint {
    NdStructure structure;
    NdChains chains;
    double fs = 0.0;
    bool closed = false;  // with the controller
    NdController controller;
};
std::vector<NdLoop> nd_loops(const std::vector<NdPoint>& points, int workers);

}  // namespace amb_fast
