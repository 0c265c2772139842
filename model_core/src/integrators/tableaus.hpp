// Coefficients of the project's one-step methods, with their sources.
#pragma once

namespace gimbal::tableau {

// Dormand-Prince 5(4), FSAL, with Dormand and Prince's continuous extension of order 4.
// J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae", J. Comput. Appl. Math. 6
// (1980) 19-26; dense output: P. J. Prince, J. R. Dormand (1981) as given in E. Hairer, S. P. Norsett,
// G. Wanner, "Solving Ordinary Differential Equations I", 2nd ed., Springer 1993, section II.6, and in
// the code DOPRI5 (subroutine CONTD5) of the same authors.
namespace dopri5 {
constexpr double c2 = 1.0 / 5.0, c3 = 3.0 / 10.0, c4 = 4.0 / 5.0, c5 = 8.0 / 9.0;
constexpr double a21 = 1.0 / 5.0;
constexpr double a31 = 3.0 / 40.0, a32 = 9.0 / 40.0;
constexpr double a41 = 44.0 / 45.0, a42 = -56.0 / 15.0, a43 = 32.0 / 9.0;
constexpr double a51 = 19372.0 / 6561.0, a52 = -25360.0 / 2187.0, a53 = 64448.0 / 6561.0, a54 = -212.0 / 729.0;
constexpr double a61 = 9017.0 / 3168.0, a62 = -355.0 / 33.0, a63 = 46732.0 / 5247.0, a64 = 49.0 / 176.0,
                 a65 = -5103.0 / 18656.0;
// Fifth-order weights (= row 7: first same as last).
constexpr double b1 = 35.0 / 384.0, b3 = 500.0 / 1113.0, b4 = 125.0 / 192.0, b5 = -2187.0 / 6784.0,
                 b6 = 11.0 / 84.0;
// Fifth minus fourth order weights: the local error estimate.
constexpr double e1 = 71.0 / 57600.0, e3 = -71.0 / 16695.0, e4 = 71.0 / 1920.0, e5 = -17253.0 / 339200.0,
                 e6 = 22.0 / 525.0, e7 = -1.0 / 40.0;
// Continuous extension.
constexpr double d1 = -12715105075.0 / 11282082432.0, d3 = 87487479700.0 / 32700410799.0,
                 d4 = -10690763975.0 / 1880347072.0, d5 = 701980252875.0 / 199316789632.0,
                 d6 = -1453857185.0 / 822651844.0, d7 = 69997945.0 / 29380423.0;
// Stability boundary on the negative real axis (|h lambda| beyond which the method is unstable),
// used by Hairer's stiffness test in DOPRI5.
constexpr double stiffness_threshold = 3.25;
}  // namespace dopri5

// RODAS4: L-stable, stiffly accurate Rosenbrock method of order 4 with an embedded method of order 3
// and a continuous extension of order 3, in the transformed variables of
// E. Hairer, G. Wanner, "Solving Ordinary Differential Equations II", 2nd ed., Springer 1996,
// section IV.7, coefficients as in the code RODAS (subroutine RODCOE,
// METH = 1). Stage i solves (I/(h gamma) - J) k_i = f(t + c_i h, y + sum_j a_ij k_j)
//                                                  + sum_j (c_ij / h) k_j + h d_i df/dt.
namespace rodas4 {
constexpr double gamma = 0.25;
constexpr double c2 = 0.386, c3 = 0.21, c4 = 0.63;
constexpr double d1 = 0.25, d2 = -0.1043, d3 = 0.1035, d4 = -0.03620000000000023;
constexpr double a21 = 1.544;
constexpr double a31 = 0.9466785280815826, a32 = 0.2557011698983284;
constexpr double a41 = 3.314825187068521, a42 = 2.896124015972201, a43 = 0.9986419139977817;
constexpr double a51 = 1.221224509226641, a52 = 6.019134481288629, a53 = 12.53708332932087,
                 a54 = -0.687886036105895;
constexpr double c21 = -5.6688;
constexpr double c31 = -2.430093356833875, c32 = -0.2063599157091915;
constexpr double c41 = -0.1073529058151375, c42 = -9.594562251023355, c43 = -20.47028614809616;
constexpr double c51 = 7.496443313967647, c52 = -10.24680431464352, c53 = -33.99990352819905,
                 c54 = 11.7089089320616;
constexpr double c61 = 8.083246795921522, c62 = -7.981132988064893, c63 = -31.52159432874371,
                 c64 = 16.31930543123136, c65 = -6.058818238834054;
// Continuous extension: y(t0 + s h) = (1 - s) y0 + s (y1 + (1 - s) (q1 + s q2)),
// q1 = sum d2j k_j, q2 = sum d3j k_j.
constexpr double d21 = 10.12623508344586, d22 = -7.487995877610167, d23 = -34.80091861555747,
                 d24 = -7.992771707568823, d25 = 1.025137723295662;
constexpr double d31 = -0.6762803392801253, d32 = 6.087714651680015, d33 = 16.43084320892478,
                 d34 = 24.76722511418386, d35 = -6.594389125716872;
}  // namespace rodas4

}  // namespace gimbal::tableau
