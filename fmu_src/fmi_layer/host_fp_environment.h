/* The host's floating-point environment, held for the length of every fmi2* call: the FMU computes
 * in the default environment (round to nearest, all exceptions masked, no flush-to-zero) whatever the
 * host set (trapping exceptions, another rounding mode, -ffast-math's FTZ/DAZ), and gives the host
 * its environment back unchanged. */
#ifndef GIMBAL_HOST_FP_ENVIRONMENT_H
#define GIMBAL_HOST_FP_ENVIRONMENT_H

#include <fenv.h>

#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#define GIMBAL_FP_X86 1
#else
#define GIMBAL_FP_X86 0
#endif

typedef struct {
    int full_restore;
    fenv_t environment;
    unsigned int mxcsr;
} HostFpEnvironment;

/* x86: MXCSR with every exception masked, round to nearest, FTZ and DAZ off (flag bits ignored). */
#define GIMBAL_DEFAULT_MXCSR 0x1F80u

static inline void enter_fmu_fp(HostFpEnvironment* host) {
#if GIMBAL_FP_X86
    /* The usual case, a host in the default environment, costs two register reads: only the SSE
     * sticky flags the FMU raises need undoing. (Its rare x87 instructions may leave x87 flags.) */
    unsigned short x87_control;
    __asm__ volatile("fnstcw %0" : "=m"(x87_control));
    host->mxcsr = _mm_getcsr();
    if ((host->mxcsr & ~0x3Fu) == GIMBAL_DEFAULT_MXCSR && (x87_control & 0x3F) == 0x3F && (x87_control & 0xC00) == 0) {
        host->full_restore = 0;
        return;
    }
#endif
    host->full_restore = 1;
    fegetenv(&host->environment);
    fesetenv(FE_DFL_ENV);
#if GIMBAL_FP_X86
    _mm_setcsr(GIMBAL_DEFAULT_MXCSR);
#endif
}

static inline void leave_fmu_fp(const HostFpEnvironment* host) {
    if (host->full_restore) {
        fesetenv(&host->environment);
        return;
    }
#if GIMBAL_FP_X86
    _mm_setcsr(host->mxcsr);
#endif
}

/* The body of an exported function: `call` (of type `type`) runs in the FMU's environment, and the
 * host gets its own back before the result is returned. Every FMU of the project (the gimbal's
 * FMI 2.0 and 3.0 wrappers, the ship-motion and controller FMUs) wraps its entry points in it. */
#define IN_FMU_FP_ENVIRONMENT(type, call)   \
    HostFpEnvironment host_environment;     \
    enter_fmu_fp(&host_environment);        \
    const type result = call;               \
    leave_fmu_fp(&host_environment);        \
    return result

#endif
