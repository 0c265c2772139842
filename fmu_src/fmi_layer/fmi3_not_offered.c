/* The FMI 3.0 functions that no FMU of the project offers, written once for the gimbal's FMI 3.0
 * binary and the small FMUs' (fmi3_face.h): the types none of them has variables of (Float32, the
 * 8- and 16-bit and the unsigned integers, Binary, Clock), clocks, configuration mode, adjoint
 * derivatives, the evaluation of discrete states and per-element dependencies. Each is refused naming
 * the function and the reason, after the state check; nothing here computes, but every entry takes
 * the FMU's floating-point environment as every other does. */
#include "fmi_layer/fmi3_face.h"
#include "fmi_layer/host_fp_environment.h"

#define OWN_INSTANCE ((FmiInstance*)instance)

FMI3_ABSENT_TYPE(Float32, fmi3Float32)
FMI3_ABSENT_TYPE(Int8, fmi3Int8)
FMI3_ABSENT_TYPE(UInt8, fmi3UInt8)
FMI3_ABSENT_TYPE(Int16, fmi3Int16)
FMI3_ABSENT_TYPE(UInt16, fmi3UInt16)
FMI3_ABSENT_TYPE(UInt32, fmi3UInt32)
FMI3_ABSENT_TYPE(UInt64, fmi3UInt64)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, size_t sizes[],
                         fmi3Binary values[], size_t nValues) {
    (void)sizes, (void)values, (void)nValues;
    IN_FMU_FP_ENVIRONMENT(fmi3Status, fmi3_refuse_absent_type(OWN_INSTANCE, "fmi3GetBinary", 0, vr, nvr));
}
fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const size_t sizes[],
                         const fmi3Binary values[], size_t nValues) {
    (void)sizes, (void)values, (void)nValues;
    IN_FMU_FP_ENVIRONMENT(fmi3Status, fmi3_refuse_absent_type(OWN_INSTANCE, "fmi3SetBinary", 1, vr, nvr));
}
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[]) {
    (void)values;
    IN_FMU_FP_ENVIRONMENT(fmi3Status, fmi3_refuse_absent_type(OWN_INSTANCE, "fmi3GetClock", 0, vr, nvr));
}
fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[]) {
    (void)values;
    IN_FMU_FP_ENVIRONMENT(fmi3Status, fmi3_refuse_absent_type(OWN_INSTANCE, "fmi3SetClock", 1, vr, nvr));
}

#define NOT_OFFERED(function, why) IN_FMU_FP_ENVIRONMENT(fmi3Status, fmi3_refuse_not_offered(OWN_INSTANCE, function, why))

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr, size_t* n) {
    (void)vr, (void)n;
    NOT_OFFERED("fmi3GetNumberOfVariableDependencies",
                "the dependencies are in <ModelStructure> (no per-element dependencies)");
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent, size_t element_indices[],
                                       fmi3ValueReference independents[], size_t independent_element_indices[],
                                       fmi3DependencyKind kinds[], size_t n) {
    (void)dependent, (void)element_indices, (void)independents, (void)independent_element_indices, (void)kinds, (void)n;
    NOT_OFFERED("fmi3GetVariableDependencies", "the dependencies are in <ModelStructure> (no per-element dependencies)");
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed, (void)sensitivity,
        (void)nSensitivity;
    NOT_OFFERED("fmi3GetAdjointDerivative", "providesAdjointDerivatives is false");
}
fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    NOT_OFFERED("fmi3EnterConfigurationMode", "the model has no structural parameters to configure after instantiation");
}
fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    NOT_OFFERED("fmi3ExitConfigurationMode", "the model has no structural parameters to configure after instantiation");
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    NOT_OFFERED("fmi3EvaluateDiscreteStates", "providesEvaluateDiscreteStates is false");
}

/* ---------------------------------------------------------------- clocks */

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Float64 a[],
                                  fmi3IntervalQualifier q[]) {
    (void)vr, (void)n, (void)a, (void)q;
    NOT_OFFERED("fmi3GetIntervalDecimal", "the model has no clocks");
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 a[],
                                   fmi3UInt64 b[], fmi3IntervalQualifier q[]) {
    (void)vr, (void)n, (void)a, (void)b, (void)q;
    NOT_OFFERED("fmi3GetIntervalFraction", "the model has no clocks");
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Float64 a[]) {
    (void)vr, (void)n, (void)a;
    NOT_OFFERED("fmi3GetShiftDecimal", "the model has no clocks");
}
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 a[],
                                fmi3UInt64 b[]) {
    (void)vr, (void)n, (void)a, (void)b;
    NOT_OFFERED("fmi3GetShiftFraction", "the model has no clocks");
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Float64 a[]) {
    (void)vr, (void)n, (void)a;
    NOT_OFFERED("fmi3SetIntervalDecimal", "the model has no clocks");
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 a[],
                                   const fmi3UInt64 b[]) {
    (void)vr, (void)n, (void)a, (void)b;
    NOT_OFFERED("fmi3SetIntervalFraction", "the model has no clocks");
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Float64 a[]) {
    (void)vr, (void)n, (void)a;
    NOT_OFFERED("fmi3SetShiftDecimal", "the model has no clocks");
}
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 a[],
                                const fmi3UInt64 b[]) {
    (void)vr, (void)n, (void)a, (void)b;
    NOT_OFFERED("fmi3SetShiftFraction", "the model has no clocks");
}
