// Drive-train components between the motors and the bodies (MODEL.md section 3).
#pragma once

namespace gimbal {

struct MotorParameters {
    double resistance = 0.0;         // Ohm
    double inductance = 0.0;         // H
    double torque_constant = 0.0;    // N.m/A
    double back_emf_constant = 0.0;  // V.s/rad
    double current_limit = 0.0;      // A
    double voltage_limit = 0.0;      // V
};

struct GearParameters {
    double ratio = 1.0;         // rotor angle / load angle
    double stiffness = 0.0;     // N.m/rad
    double damping = 0.0;       // N.m.s/rad
    double half_backlash = 0.0; // eta, rad
};

// (2.142 - 2.145): the input voltage is clamped once per communication step.
inline double clamp_voltage(const MotorParameters& motor, double commanded_voltage) {
    if (commanded_voltage > motor.voltage_limit) return motor.voltage_limit;
    if (commanded_voltage < -motor.voltage_limit) return -motor.voltage_limit;
    return commanded_voltage;
}

// RL armature circuit (2.62): di/dt.
inline double armature_current_rate(const MotorParameters& motor, double voltage, double current, double rotor_speed) {
    return (voltage - motor.resistance * current - motor.back_emf_constant * rotor_speed) / motor.inductance;
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

}  // namespace gimbal
