// The SUNDIALS reference methods under the hybrid layer: the backend (CVODE or ARKODE) finds roots of
// the event functions itself; this class runs the event loop, the chattering guard and the statistics.
#pragma once

#include <vector>

#include <sundials/sundials_context.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nvector.h>

#include "gimbal/integrators/integrator.hpp"

namespace gimbal {

class SundialsIntegrator : public HybridIntegrator {
public:
    ~SundialsIntegrator() override;
    bool restart(double time, const double* state) override;
    bool advance(double end_time, double* state) override;
    IntegratorStatistics statistics() const override;
    void set_statistics(const IntegratorStatistics& totals) override { totals_ = totals; }

protected:
    enum class Outcome { reached_end, root, failure };

    SundialsIntegrator(HybridSystem& system, const IntegratorSettings& settings, MessageSink error_sink,
                       MessageSink event_sink);

    // The context and y_; false when memory runs out (restart() then reports it).
    bool create_vector();

    // SUNDIALS 6 dereferences what N_VClone, N_VCloneEmpty and SUNMatClone return without checking it
    // (it sets the clone's context): a clone that fails to allocate crashes inside CVODE or ARKODE. So
    // y_, the Jacobian of create_matrix() and all their clones clone themselves from spares, made by
    // these two before each creation of the solver memory, while a failure can still be reported.
    // count: as many clones as the creation and the first step make (at most kMaxSpareVectors). Empty
    // clones (CVODE's difference-quotient Jacobian makes and destroys one at every evaluation) go
    // back to their spares when destroyed.
    bool reserve_spare_vectors(int count);
    bool reserve_spare_matrix();
    // A dense size_ x size_ matrix that clones itself from the spare matrix; nullptr when memory runs out.
    SUNMatrix create_matrix();

    // Backend: (re)initialize at (time, y_), integrate towards end_time stopping there exactly, report
    // root directions, and count work since the last (re)initialization.
    virtual bool backend_restart(double time) = 0;
    virtual Outcome backend_advance(double end_time, double& reached) = 0;
    virtual void backend_roots(int* directions) = 0;
    virtual IntegratorStatistics backend_counters() const = 0;

    // Callbacks with SUNDIALS signatures, shared by the backends (user data = this).
    static int right_hand_side(sunrealtype time, N_Vector y, N_Vector ydot, void* user_data);
    static int event_functions(sunrealtype time, N_Vector y, sunrealtype* values, void* user_data);
    static void forward_error(int code, const char* module, const char* function, char* message, void* user_data);

    // Called from SUNDIALS' C code: no exception may pass through it.
    template <class Body>
    static int without_exceptions(int failure, Body&& body) noexcept {
        try {
            return body();
        } catch (...) {
            return failure;
        }
    }

    HybridSystem& system_;
    IntegratorSettings settings_;
    MessageSink error_sink_, event_sink_;
    int size_;
    SUNContext context_ = nullptr;
    N_Vector y_ = nullptr;
    bool initialized_ = false;
    std::vector<int> root_directions_;

    static constexpr int kMaxSpareVectors = 48;

private:
    static constexpr int kSpareEmptyVectors = 2;
    N_Vector make_vector();
    N_Vector make_empty_vector();
    static N_Vector clone_vector(N_Vector original);
    static N_Vector clone_vector_empty(N_Vector original);
    static void release_empty_vector(N_Vector vector);
    static SUNMatrix clone_matrix(SUNMatrix original);

    N_Vector spare_vectors_[kMaxSpareVectors] = {};
    int spare_vector_count_ = 0;
    N_Vector spare_empty_vectors_[kSpareEmptyVectors] = {};
    int spare_empty_vector_count_ = 0;
    SUNMatrix spare_matrix_ = nullptr;

    IntegratorStatistics totals_;  // of finished backend runs (their counters reset at each restart)
    ChatteringMemory chattering_;
};

std::unique_ptr<HybridIntegrator> make_cvode_backend(HybridSystem&, const IntegratorSettings&,
                                                     HybridIntegrator::MessageSink, HybridIntegrator::MessageSink);
std::unique_ptr<HybridIntegrator> make_arkode_backend(HybridSystem&, const IntegratorSettings&,
                                                      HybridIntegrator::MessageSink, HybridIntegrator::MessageSink);

}  // namespace gimbal
