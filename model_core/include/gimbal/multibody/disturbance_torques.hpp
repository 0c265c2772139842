// Disturbances a real pedestal has besides its drive train (docs/physics.md section 4.5): the cable
// restraint across each joint and the cogging of each motor. Both are smooth torques of the relative
// angle (and rate) of two bodies, so they act on one generalized coordinate each and have no mode: pure
// functions here, applied by the dynamics (model/gimbal_model.cpp) only when a parameter switched them on.
#pragma once

#include <cmath>

namespace gimbal {

// A cable (or slip-ring-less harness) across a joint: a torsional spring and damper between the joint's
// two bodies. Torque on the outer body, the opposite on the inner one:
// T = -k (q - q_0) - c q'   (q the joint angle: alpha for cable 1, beta for cable 2).
struct CableRestraint {
    double stiffness = 0.0;      // k, N.m/rad
    double damping = 0.0;        // c, N.m.s/rad
    double neutral_angle = 0.0;  // q_0, rad: where the cable exerts no torque
    bool present() const { return stiffness != 0.0 || damping != 0.0; }
};

inline double cable_torque(const CableRestraint& cable, double angle, double rate) {
    return -cable.stiffness * (angle - cable.neutral_angle) - cable.damping * rate;
}

// The spring's stored energy, k (q - q_0)^2 / 2.
inline double cable_energy(const CableRestraint& cable, double angle) {
    const double twist = angle - cable.neutral_angle;
    return 0.5 * cable.stiffness * twist * twist;
}

// Cogging (detent torque) of a motor: the rotor's magnets pulled towards the stator's teeth, a torque
// of the rotor angle q_m relative to the stator, n periods per revolution:
// T = -T_c sin(n q_m + phase), conservative with the potential V = (T_c / n) (1 - cos(n q_m + phase)),
// T = -dV/dq_m. The rotor rests (V = 0, stable) at the detents n q_m + phase = 2 pi k.
struct Cogging {
    double amplitude = 0.0;  // T_c, N.m
    int periods = 1;         // n, ripple periods per revolution of the rotor
    double phase = 0.0;      // rad
    bool present() const { return amplitude != 0.0; }
};

inline double cogging_torque(const Cogging& cogging, double rotor_angle) {
    return -cogging.amplitude * std::sin(cogging.periods * rotor_angle + cogging.phase);
}

// dT/dq_m: the element's (angle-dependent) stiffness, negative at a detent.
inline double cogging_torque_slope(const Cogging& cogging, double rotor_angle) {
    return -cogging.amplitude * cogging.periods * std::cos(cogging.periods * rotor_angle + cogging.phase);
}

inline double cogging_energy(const Cogging& cogging, double rotor_angle) {
    return cogging.amplitude / cogging.periods * (1.0 - std::cos(cogging.periods * rotor_angle + cogging.phase));
}

// The elements of both axes (axis 0 azimuth, 1 elevation). `active` is decided once from the parameters
// (ModelParameters::finalize): when every element is off the dynamics never look at them, so a model
// without disturbances computes exactly what it did before they existed, bit for bit, at no cost.
struct DisturbanceParameters {
    CableRestraint cable[2];  // across the joint of the axis's load: carrier-body 1, body 1-body 2
    Cogging cogging[2];       // of the axis's motor: rotor R1 on the carrier, rotor R2 on body 1
    bool active = false;
    bool any_present() const {
        return cable[0].present() || cable[1].present() || cogging[0].present() || cogging[1].present();
    }
};

}  // namespace gimbal
