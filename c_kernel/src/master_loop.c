#include "gimbal_kernel/master_loop.h"

enum { kFailedNothing = 0, kFailedGetReal = 1, kFailedGetInteger = 2, kFailedSetReal = 3, kFailedDoStep = 4 };

const char* gimbal_master_loop_call_name(int code) {
    static const char* const kNames[] = {NULL, "fmi2GetReal", "fmi2GetInteger", "fmi2SetReal", "fmi2DoStep"};
    return code > kFailedNothing && code <= kFailedDoStep ? kNames[code] : NULL;
}

int gimbal_master_loop(GimbalMasterLoop* m, long first, long last) {
    for (long k = first; k <= last; ++k) {
        m->failed_step = k;
        double* y = m->rec_real + k * m->real_count;
        if (m->get_real(m->component, m->real_vrs, (size_t)m->real_count, y) > 1) return m->failed_call = kFailedGetReal;
        if (m->mode_count &&
            m->get_integer(m->component, m->mode_vrs, (size_t)m->mode_count, m->rec_mode + k * m->mode_count) > 1)
            return m->failed_call = kFailedGetInteger;
        double measured[7] = {y[m->i_alpha],   y[m->i_beta],      y[m->i_gyro[0]],  y[m->i_gyro[1]],
                              y[m->i_gyro[2]], y[m->i_alpha_dot], y[m->i_beta_dot]};
        gimbal_sensors_measure(&m->sensors, k, measured);
        double* u = m->u_cmd + 2 * k;
        gimbal_controller_step(&m->controller, k, m->h, measured, NULL, u, m->refs + 2 * k);
        if (m->u_asked) m->u_asked[2 * k] = m->controller.asked[0], m->u_asked[2 * k + 1] = m->controller.asked[1];
        if (k == m->n) break;
        /* The voltage applied over [t_k, t_k+1]: the command of `delay` steps before, 0 V until one is due. */
        double* row = m->inputs + k * m->input_count;
        if (m->delay == 0) {
            row[0] = u[0], row[1] = u[1];
        } else if (k >= m->delay) {
            row[0] = m->u_cmd[2 * (k - m->delay)], row[1] = m->u_cmd[2 * (k - m->delay) + 1];
        } else {
            row[0] = 0.0, row[1] = 0.0;
        }
        if (m->set_real(m->component, m->input_vrs, (size_t)m->input_count, row) > 1) return m->failed_call = kFailedSetReal;
        if (m->do_step(m->component, (double)k * m->h, m->h, 1) > 1) return m->failed_call = kFailedDoStep;
    }
    return kFailedNothing;
}
