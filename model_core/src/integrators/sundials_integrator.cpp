#include <cstdint>
#include "sundials_integrator.hpp"

#include "gimbal/hybrid_system/event_handling.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include <nvector/nvector_serial.h>
#include <sundials/sundials_config.h>
#include <sundials/sundials_logger.h>
#include <sunmatrix/sunmatrix_dense.h>

namespace gimbal {
namespace {

// The content of the backends' vectors and Jacobian: SUNDIALS' own, then the integrator whose spares
// the clones come from. SUNDIALS reaches the content only through NV_CONTENT_S / SM_CONTENT_D, which
// see the first member, and frees it with free(), as it was allocated.
struct VectorContent {
    _N_VectorContent_Serial sundials;
    SundialsIntegrator* owner;
};

struct MatrixContent {
    _SUNMatrixContent_Dense sundials;
    SundialsIntegrator* owner;
};

// Replaces the content SUNDIALS made for a new vector or matrix by its Content; false (the content
// untouched) when memory runs out.
template <class Content>
bool attach_owner(void*& content, SundialsIntegrator* owner) {
    auto* extended = static_cast<Content*>(std::malloc(sizeof(Content)));
    if (extended == nullptr) return false;
    extended->sundials = *static_cast<decltype(extended->sundials)*>(content);
    extended->owner = owner;
    std::free(content);
    content = extended;
    return true;
}

SundialsIntegrator* owner_of(N_Vector vector) { return static_cast<VectorContent*>(vector->content)->owner; }
SundialsIntegrator* owner_of(SUNMatrix matrix) { return static_cast<MatrixContent*>(matrix->content)->owner; }

}  // namespace

SundialsIntegrator::SundialsIntegrator(HybridSystem& system, const IntegratorSettings& settings,
                                       MessageSink error_sink, MessageSink event_sink)
    : system_(system),
      settings_(settings),
      error_sink_(std::move(error_sink)),
      event_sink_(std::move(event_sink)),
      size_(system.state_size()),
      root_directions_(system.event_count(), 0) {}

SundialsIntegrator::~SundialsIntegrator() {
    for (int k = 0; k < spare_vector_count_; ++k) N_VDestroy(spare_vectors_[k]);
    for (int k = 0; k < spare_empty_vector_count_; ++k) N_VDestroy_Serial(spare_empty_vectors_[k]);
    if (spare_matrix_ != nullptr) SUNMatDestroy(spare_matrix_);
    if (y_ != nullptr) N_VDestroy(y_);
    if (context_ != nullptr) SUNContext_Free(&context_);
}

N_Vector SundialsIntegrator::make_vector() {
    N_Vector vector = N_VNew_Serial(size_, context_);
    if (vector == nullptr) return nullptr;
    if (!attach_owner<VectorContent>(vector->content, this)) {
        N_VDestroy(vector);
        return nullptr;
    }
    vector->ops->nvclone = clone_vector;
    vector->ops->nvcloneempty = clone_vector_empty;
    return vector;
}

// A vector without data (SUNDIALS points it at arrays of its own), kept for reuse when destroyed.
N_Vector SundialsIntegrator::make_empty_vector() {
    N_Vector vector = N_VCloneEmpty_Serial(y_);
    if (vector == nullptr) return nullptr;
    if (!attach_owner<VectorContent>(vector->content, this)) {
        N_VDestroy(vector);
        return nullptr;
    }
    vector->ops->nvdestroy = release_empty_vector;
    return vector;
}

N_Vector SundialsIntegrator::clone_vector(N_Vector original) {
    SundialsIntegrator* owner = owner_of(original);
    if (owner->spare_vector_count_ > 0) return owner->spare_vectors_[--owner->spare_vector_count_];
    // More clones than the backend reserved: still right, but no longer safe from out-of-memory.
    return owner->make_vector();
}

N_Vector SundialsIntegrator::clone_vector_empty(N_Vector original) {
    SundialsIntegrator* owner = owner_of(original);
    if (owner->spare_empty_vector_count_ > 0) return owner->spare_empty_vectors_[--owner->spare_empty_vector_count_];
    // More at once than reserved: still right, but no longer safe from out-of-memory.
    return owner->make_empty_vector();
}

void SundialsIntegrator::release_empty_vector(N_Vector vector) {
    SundialsIntegrator* owner = owner_of(vector);
    NV_DATA_S(vector) = nullptr;
    if (owner->spare_empty_vector_count_ < kSpareEmptyVectors)
        owner->spare_empty_vectors_[owner->spare_empty_vector_count_++] = vector;
    else
        N_VDestroy_Serial(vector);
}

bool SundialsIntegrator::create_vector() {
    // One context per instance: SUNDIALS keeps no state shared between FMU instances.
    if (SUNContext_Create(nullptr, &context_) != 0) {
        context_ = nullptr;
        return false;
    }
    y_ = make_vector();
    return y_ != nullptr;
}

bool SundialsIntegrator::reserve_spare_vectors(int count) {
    while (spare_vector_count_ < std::min(count, kMaxSpareVectors)) {
        N_Vector spare = make_vector();
        if (spare == nullptr) return false;
        spare_vectors_[spare_vector_count_++] = spare;
    }
    while (spare_empty_vector_count_ < kSpareEmptyVectors) {
        N_Vector spare = make_empty_vector();
        if (spare == nullptr) return false;
        spare_empty_vectors_[spare_empty_vector_count_++] = spare;
    }
    return true;
}

bool SundialsIntegrator::reserve_spare_matrix() {
    if (spare_matrix_ == nullptr) spare_matrix_ = SUNDenseMatrix(size_, size_, context_);
    return spare_matrix_ != nullptr;
}

SUNMatrix SundialsIntegrator::create_matrix() {
    SUNMatrix matrix = SUNDenseMatrix(size_, size_, context_);
    if (matrix == nullptr) return nullptr;
    if (!attach_owner<MatrixContent>(matrix->content, this)) {
        SUNMatDestroy(matrix);
        return nullptr;
    }
    matrix->ops->clone = clone_matrix;
    return matrix;
}

SUNMatrix SundialsIntegrator::clone_matrix(SUNMatrix original) {
    SundialsIntegrator* owner = owner_of(original);
    SUNMatrix clone = owner->spare_matrix_;
    owner->spare_matrix_ = nullptr;
    // A second clone: still right, but no longer safe from out-of-memory.
    return clone != nullptr ? clone : SUNMatClone_Dense(original);
}

void SundialsIntegrator::forward_error(int code, const char* module, const char* function, char* message,
                                     void* user_data) {
    auto* self = static_cast<SundialsIntegrator*>(user_data);
    if (code >= 0) return;  // warnings are not failures; the caller reports what matters
    // Out of memory here loses this detail only: the caller still reports the failure.
    without_exceptions(0, [&] {
        self->error_sink_(std::string(module) + "::" + function + ": " + message);
        return 0;
    });
}

int SundialsIntegrator::right_hand_side(sunrealtype time, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<SundialsIntegrator*>(user_data);
    // Recoverable failure: the integrator retries with a smaller step.
    return without_exceptions(-1, [&] {
        return self->system_.derivative(time, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)) ? 0 : 1;
    });
}

int SundialsIntegrator::event_functions(sunrealtype time, N_Vector y, sunrealtype* values, void* user_data) {
    auto* self = static_cast<SundialsIntegrator*>(user_data);
    return without_exceptions(-1, [&] {
        if (time < self->chattering_.dwell_until) {
            std::fill(values, values + self->root_directions_.size(), 1.0);
            return 0;
        }
        self->system_.event_functions(time, N_VGetArrayPointer(y), values);
        return 0;
    });
}

bool SundialsIntegrator::restart(double time, const double* state) {
    if (y_ == nullptr) {
        error_sink_("the integrator could not be created (out of memory)");
        return false;
    }
    if (initialized_) {
        const IntegratorStatistics run = backend_counters();
        totals_.steps += run.steps;
        totals_.rhs_evaluations += run.rhs_evaluations;
        totals_.jacobian_evaluations += run.jacobian_evaluations;
    }
    std::copy(state, state + size_, N_VGetArrayPointer(y_));
    initialized_ = backend_restart(time);
    return initialized_;
}

bool SundialsIntegrator::advance(double end_time, double* state) {
    double* y = N_VGetArrayPointer(y_);
    // One budget of internal steps for the whole call: restarts after mode changes reset the
    // backend's own count, and switches 10-100 ns apart would otherwise run on without bound.
    const std::int64_t steps_at_start = statistics().steps;
    std::int64_t events_here = 0;
    for (;;) {
        double reached = 0.0;
        const Outcome outcome = backend_advance(end_time, reached);
        if (outcome == Outcome::failure) return false;
        std::copy(y, y + size_, state);
        if (outcome == Outcome::reached_end) return true;
        if (statistics().steps - steps_at_start > settings_.max_steps) {
            std::ostringstream s;
            s.precision(17);
            s << "more than solver.max_steps = " << settings_.max_steps << " internal steps (" << events_here
              << " mode changes) before t = " << reached << ": the inputs or parameters drive switching faster than "
              << "the model can follow";
            error_sink_(s.str());
            return false;
        }

        backend_roots(root_directions_.data());
        double before[64];
        const bool tracked = size_ <= 64;
        if (tracked) std::copy(state, state + size_, before);
        const int changes = switch_modes(system_, reached, state, root_directions_.data(), settings_.event_handling,
                                         event_sink_, reached);
        // A projection without a mode change (e.g. theta_b clamped back onto a stop) must not be lost.
        const bool projected = tracked && !std::equal(state, state + size_, before);
        totals_.events += changes;
        events_here += changes;
        // CVODE and ARKODE locate roots to about 100 ulp of the time: the window itself resolves them.
        if (record_mode_change(chattering_, settings_.event_handling, reached, 0.0, event_sink_)) ++totals_.zeno_holds;
        // New modes change the right-hand side: restart there, from the (possibly projected) state. A
        // root that changed nothing (a grazing touch) needs no restart: the integrator carries on.
        if ((changes > 0 || projected) && !restart(reached, state)) return false;
        if (reached >= end_time) return true;
    }
}

IntegratorStatistics SundialsIntegrator::statistics() const {
    IntegratorStatistics stats = totals_;
    if (!initialized_) return stats;
    const IntegratorStatistics run = backend_counters();
    stats.steps += run.steps;
    stats.rhs_evaluations += run.rhs_evaluations;
    stats.jacobian_evaluations += run.jacobian_evaluations;
    return stats;
}

}  // namespace gimbal

// ---------------------------------------------------------------------------- SUNDIALS' logger
// SUNContext_Create makes a SUNLogger, and SUNDIALS 6's (sundials_logger.c) is not safe when memory
// runs out: it writes through an unchecked malloc (SUNHashMap_New), and when the next one fails it
// keeps a freed pointer that SUNContext_Free frees again. Both crash the host. These definitions
// stand in for that file, so the static link never takes it from libsundials_generic: a logger of one
// checked allocation that writes nothing. Nothing is lost: the FMU must never print, and SUNDIALS'
// own logger writes to stdout/stderr (errors reach the FMU's log through forward_error instead).
#if SUNDIALS_VERSION_MAJOR != 6
#error "the SUNLogger stand-in below follows the SUNDIALS 6 API"
#endif

struct SUNLogger_ {
    int output_rank;
};

extern "C" {

int SUNLogger_Create(void*, int output_rank, SUNLogger* logger) {
    if (logger == nullptr) return -1;
    *logger = static_cast<SUNLogger>(std::malloc(sizeof(SUNLogger_)));
    if (*logger == nullptr) return -1;
    (*logger)->output_rank = output_rank;
    return 0;
}

int SUNLogger_CreateFromEnv(void* comm, SUNLogger* logger) { return SUNLogger_Create(comm, 0, logger); }

int SUNLogger_SetErrorFilename(SUNLogger logger, const char*) { return logger != nullptr ? 0 : -1; }
int SUNLogger_SetWarningFilename(SUNLogger logger, const char*) { return logger != nullptr ? 0 : -1; }
int SUNLogger_SetDebugFilename(SUNLogger logger, const char*) { return logger != nullptr ? 0 : -1; }
int SUNLogger_SetInfoFilename(SUNLogger logger, const char*) { return logger != nullptr ? 0 : -1; }
int SUNLogger_QueueMsg(SUNLogger logger, SUNLogLevel, const char*, const char*, const char*, ...) {
    return logger != nullptr ? 0 : -1;
}
int SUNLogger_Flush(SUNLogger logger, SUNLogLevel) { return logger != nullptr ? 0 : -1; }

int SUNLogger_GetOutputRank(SUNLogger logger, int* output_rank) {
    if (logger == nullptr || output_rank == nullptr) return -1;
    *output_rank = logger->output_rank;
    return 0;
}

int SUNLogger_Destroy(SUNLogger* logger) {
    if (logger == nullptr) return 0;
    std::free(*logger);
    *logger = nullptr;
    return 0;
}

}  // extern "C"
