// The FMU's shared object loaded with dlopen, as a host loads it: its fmi2* functions, a logger
// that keeps every message, and the GUID and value references read from modelDescription.xml.
#pragma once

#include <dlfcn.h>

#include <cstdarg>
#include <cstdlib>
#include <type_traits>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "fmi2FunctionTypes.h"

namespace fmu_loader {

struct Api {
    void* handle = nullptr;
    fmi2InstantiateTYPE* instantiate;
    fmi2FreeInstanceTYPE* freeInstance;
    fmi2SetupExperimentTYPE* setupExperiment;
    fmi2EnterInitializationModeTYPE* enterInitializationMode;
    fmi2ExitInitializationModeTYPE* exitInitializationMode;
    fmi2TerminateTYPE* terminate;
    fmi2ResetTYPE* reset;
    fmi2SetDebugLoggingTYPE* setDebugLogging;
    fmi2SetRealTYPE* setReal;
    fmi2GetRealTYPE* getReal;
    fmi2SetIntegerTYPE* setInteger;
    fmi2GetIntegerTYPE* getInteger;
    fmi2DoStepTYPE* doStep;
    fmi2GetFMUstateTYPE* getFMUstate;
    fmi2SetFMUstateTYPE* setFMUstate;
    fmi2FreeFMUstateTYPE* freeFMUstate;
    fmi2SerializedFMUstateSizeTYPE* serializedFMUstateSize;
    fmi2SerializeFMUstateTYPE* serializeFMUstate;
    fmi2DeSerializeFMUstateTYPE* deSerializeFMUstate;
    // Model Exchange
    fmi2EnterEventModeTYPE* enterEventMode;
    fmi2NewDiscreteStatesTYPE* newDiscreteStates;
    fmi2EnterContinuousTimeModeTYPE* enterContinuousTimeMode;
    fmi2SetTimeTYPE* setTime;
    fmi2SetContinuousStatesTYPE* setContinuousStates;
    fmi2GetDerivativesTYPE* getDerivatives;
    fmi2GetEventIndicatorsTYPE* getEventIndicators;
    fmi2GetContinuousStatesTYPE* getContinuousStates;

    bool load(const char* path) {
        void* opened = dlopen(path, RTLD_NOW | RTLD_LOCAL);
        if (opened == nullptr) {
            std::fprintf(stderr, "dlopen(%s) failed: %s\n", path, dlerror());
            return false;
        }
        return bind(opened);
    }

    // The functions of an object the caller opened.
    bool bind(void* opened) {
        handle = opened;
        bool ok = true;
        auto find = [&](auto& pointer, const char* name) {
            pointer = reinterpret_cast<std::remove_reference_t<decltype(pointer)>>(dlsym(handle, name));
            if (pointer == nullptr) {
                std::fprintf(stderr, "%s is not exported\n", name);
                ok = false;
            }
        };
        find(instantiate, "fmi2Instantiate");
        find(freeInstance, "fmi2FreeInstance");
        find(setupExperiment, "fmi2SetupExperiment");
        find(enterInitializationMode, "fmi2EnterInitializationMode");
        find(exitInitializationMode, "fmi2ExitInitializationMode");
        find(terminate, "fmi2Terminate");
        find(reset, "fmi2Reset");
        find(setDebugLogging, "fmi2SetDebugLogging");
        find(setReal, "fmi2SetReal");
        find(getReal, "fmi2GetReal");
        find(setInteger, "fmi2SetInteger");
        find(getInteger, "fmi2GetInteger");
        find(doStep, "fmi2DoStep");
        find(getFMUstate, "fmi2GetFMUstate");
        find(setFMUstate, "fmi2SetFMUstate");
        find(freeFMUstate, "fmi2FreeFMUstate");
        find(serializedFMUstateSize, "fmi2SerializedFMUstateSize");
        find(serializeFMUstate, "fmi2SerializeFMUstate");
        find(deSerializeFMUstate, "fmi2DeSerializeFMUstate");
        find(enterEventMode, "fmi2EnterEventMode");
        find(newDiscreteStates, "fmi2NewDiscreteStates");
        find(enterContinuousTimeMode, "fmi2EnterContinuousTimeMode");
        find(setTime, "fmi2SetTime");
        find(setContinuousStates, "fmi2SetContinuousStates");
        find(getDerivatives, "fmi2GetDerivatives");
        find(getEventIndicators, "fmi2GetEventIndicators");
        find(getContinuousStates, "fmi2GetContinuousStates");
        return ok;
    }
};

// Messages of one instance; the environment pointer of the callbacks points here.
struct Log {
    std::vector<std::pair<fmi2Status, std::string>> messages;
    void clear() { messages.clear(); }
    bool last_contains(const std::string& text) const {
        return !messages.empty() && messages.back().second.find(text) != std::string::npos;
    }
    std::string last() const { return messages.empty() ? std::string("(nothing logged)") : messages.back().second; }
};

inline void record_message(fmi2ComponentEnvironment environment, fmi2String, fmi2Status status, fmi2String,
                           fmi2String message, ...) {
    static_cast<Log*>(environment)->messages.emplace_back(status, message != nullptr ? message : "");
}

inline fmi2CallbackFunctions callbacks_for(Log& log) {
    return fmi2CallbackFunctions{record_message, std::calloc, std::free, nullptr, &log};
}

struct ModelDescription {
    std::string guid;
    std::map<std::string, unsigned> value_reference;

    bool read(const char* path) {
        std::ifstream file(path);
        std::stringstream buffer;
        buffer << file.rdbuf();
        const std::string text = buffer.str();
        guid = attribute(text, text.find("<fmiModelDescription"), "guid");
        for (size_t pos = text.find("<ScalarVariable"); pos != std::string::npos;
             pos = text.find("<ScalarVariable", pos + 1))
            value_reference[attribute(text, pos, "name")] =
                static_cast<unsigned>(std::stoul(attribute(text, pos, "valueReference")));
        return !guid.empty() && !value_reference.empty();
    }

    unsigned vr(const std::string& name) const { return value_reference.at(name); }

private:
    static std::string attribute(const std::string& text, size_t from, const std::string& key) {
        if (from == std::string::npos) return {};
        const size_t start = text.find(" " + key + "=\"", from);
        if (start == std::string::npos) return {};
        const size_t value = start + key.size() + 3;
        return text.substr(value, text.find('"', value) - value);
    }
};

}  // namespace fmu_loader
