// The guard of every entry of the core that C calls (c_api.cpp's gimbal_core_*, the FMU's table in
// fmu_model_table.cpp): no C++ exception crosses into C. Each becomes GIMBAL_ERROR and a message
// handed to `report`, which must not allocate (it is called when memory has run out).
#pragma once

#include <exception>
#include <new>

#include "gimbal/gimbal_status.h"

namespace gimbal {

template <class Report, class Body>
GimbalStatus guarded_entry(Report&& report, Body&& body) noexcept {
    try {
        return body();
    } catch (const std::bad_alloc&) {
        report("out of memory; the instance is left as it was before the call");
    } catch (const std::exception& error) {
        report(error.what());
    } catch (...) {
        report("internal error (an unknown C++ exception)");
    }
    return GIMBAL_ERROR;
}

}  // namespace gimbal
