// Drive-train components between the motors and the bodies (docs/physics.md section 4), each a pure
// function of its own inputs so that it can be tested against the seed's equations in isolation.
#pragma once

#include <algorithm>

namespace gimbal {

struct MotorParameters {
    double resistance = 0.0;         // Ohm
    double inductance = 0.0;         // H
    double torque_constant = 0.0;    // N.m/A
    double back_emf_constant = 0.0;  // V.s/rad
    double current_limit = 0.0;      // A
    double voltage_limit = 0.0;      // V
};

// The servo amplifier of a current-commanded motor (docs/physics.md section 4.6): an analog PI current
// loop whose output is limited by the bus voltage (the motor's voltage_limit, motor<j>.U_L). The gains
// are the ones in use: amplifier<j>.K_p and K_i as given, or derived from the bandwidth when given as 0.
struct AmplifierParameters {
    double bandwidth = 2000.0;          // f_c, Hz
    double proportional_gain = 0.0;     // K_p, V/A
    double integral_gain = 0.0;         // K_i, V/(A.s)
    bool back_emf_feedforward = true;   // adds k_emf * rotor speed to the output
};

// Pole-zero cancellation: K_p = 2 pi f_c L, K_i = 2 pi f_c R make the locked-rotor current loop
// (K_p s + K_i) / (L s^2 + (R + K_p) s + K_i) = 2 pi f_c / (s + 2 pi f_c), first order at f_c.
inline double cancelling_proportional_gain(const MotorParameters& motor, double bandwidth) {
    return 2.0 * 3.14159265358979323846 * bandwidth * motor.inductance;
}
inline double cancelling_integral_gain(const MotorParameters& motor, double bandwidth) {
    return 2.0 * 3.14159265358979323846 * bandwidth * motor.resistance;
}

struct GearParameters {
    double ratio = 1.0;         // rotor angle / load angle
    double stiffness = 0.0;     // N.m/rad
    double damping = 0.0;       // N.m.s/rad
    double half_backlash = 0.0; // eta, rad
};

struct DryFrictionParameters {
    double slip_torque = 0.0;      // T_din
    double breakaway_torque = 0.0; // T_max; 0 = no dry friction
    double stick_speed = 0.0;      // w_min
    double damping_factor = 0.0;   // mu
    bool present() const { return breakaway_torque > 0.0; }
    // (2.104)
    double numerical_damping() const { return damping_factor * breakaway_torque / stick_speed; }
};

// (2.142 - 2.145): the input voltage is clamped once per communication step.
inline double clamp_voltage(const MotorParameters& motor, double commanded_voltage) {
    return std::clamp(commanded_voltage, -motor.voltage_limit, motor.voltage_limit);
}

// RL armature circuit (2.62): di/dt.
inline double armature_current_rate(const MotorParameters& motor, double voltage, double current, double rotor_speed) {
    return (voltage - motor.resistance * current - motor.back_emf_constant * rotor_speed) / motor.inductance;
}

// The current the circuit would settle to at this speed: the limiter (2.63 - 2.69) holds i at +-i_L
// only while this lies beyond the limit.
inline double unlimited_steady_current(const MotorParameters& motor, double voltage, double rotor_speed) {
    return (voltage - motor.back_emf_constant * rotor_speed) / motor.resistance;
}

inline double electromagnetic_torque(const MotorParameters& motor, double current) {
    return motor.torque_constant * current;
}

// Gear deflection theta_d = q_m / N - q_l (2.79) and its rate (2.80).
inline double gear_deflection(const GearParameters& gear, double rotor_angle, double load_angle) {
    return rotor_angle / gear.ratio - load_angle;
}

// Shaft torque (2.77) on the load side; the rotor receives -T_E / N (2.75).
inline double gear_shaft_torque(const GearParameters& gear, double deflection, double deflection_rate,
                                double backlash, double backlash_rate) {
    return gear.stiffness * (deflection - backlash) + gear.damping * (deflection_rate - backlash_rate);
}

// X of (2.81): the backlash rate inside the gap.
inline double free_backlash_rate(const GearParameters& gear, double deflection, double deflection_rate, double backlash) {
    return deflection_rate + gear.stiffness / gear.damping * (deflection - backlash);
}

// (2.81) as a whole, for a contact side -1 / 0 / +1 (used by the unit tests to check the modes).
inline double backlash_rate(const GearParameters& gear, double deflection, double deflection_rate, double backlash,
                            int contact_side) {
    const double x = free_backlash_rate(gear, deflection, deflection_rate, backlash);
    if (contact_side > 0) return std::min(0.0, x);
    if (contact_side < 0) return std::max(0.0, x);
    return x;
}

}  // namespace gimbal
