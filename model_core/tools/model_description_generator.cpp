// Writes the parts of modelDescription.xml that follow from the variable tables, so that the names,
// value references, types, units, bounds and start values the FMU serves can never drift from what it
// declares; refuses a table that breaks the rules below (undefined unit, rad-based variable without its
// display unit, start outside its bounds, unknown enumeration type, ...).
// Usage: gimbal_model_description_generator [--fmi3] <units.xml> <variables.xml> <structure.xml> <types.xml>
//                                           <default_tolerance.txt>
// (--fmi3: the parts of the FMI 3.0 model description, modelDescription3.xml.in)
// The last is the DefaultExperiment's tolerance: the start value of solver.rtol. Next to it (FMI 2.0) it
// also writes event_indicators.txt (numberOfEventIndicators) and vendor_annotations.xml (the mode outputs
// of the switching elements), both from their one declaration, gimbal/switching_elements.def.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <algorithm>
#include <vector>

#include "gimbal/gimbal_c_api.h"
#include "gimbal/model/variable_groups.hpp"
#include "gimbal/model/variables.hpp"

namespace {

struct UnitDefinition {
    const char* name;
    const char* base_unit;     // attributes of <BaseUnit>
    const char* display_unit;  // its <DisplayUnit>, or empty; every variable of the unit must show in it
};

// value in the display unit = factor * value in the unit (+ offset, 0 for all of these)
const char* const kDegreesPerRadian = "57.29577951308232";  // 180 / pi

const UnitDefinition kUnits[] = {
    {"1", "", ""},
    {"rad", "rad=\"1\"", "deg"},
    {"rad/s", "s=\"-1\" rad=\"1\"", "deg/s"},
    {"rad/s2", "s=\"-2\" rad=\"1\"", "deg/s2"},
    {"s", "s=\"1\"", ""},
    {"m", "m=\"1\"", ""},
    {"m/s", "m=\"1\" s=\"-1\"", ""},
    {"m/s2", "m=\"1\" s=\"-2\"", ""},
    {"kg", "kg=\"1\"", ""},
    {"kg.m2", "kg=\"1\" m=\"2\"", ""},
    {"V", "kg=\"1\" m=\"2\" s=\"-3\" A=\"-1\"", ""},
    {"A", "A=\"1\"", ""},
    {"A/s", "A=\"1\" s=\"-1\"", ""},
    {"W", "kg=\"1\" m=\"2\" s=\"-3\"", ""},
    {"Ohm", "kg=\"1\" m=\"2\" s=\"-3\" A=\"-2\"", ""},
    {"H", "kg=\"1\" m=\"2\" s=\"-2\" A=\"-2\"", ""},
    {"N.m", "kg=\"1\" m=\"2\" s=\"-2\"", ""},
    {"J", "kg=\"1\" m=\"2\" s=\"-2\"", ""},
    {"N.m/A", "kg=\"1\" m=\"2\" s=\"-2\" A=\"-1\"", ""},
    {"V.s/rad", "kg=\"1\" m=\"2\" s=\"-2\" A=\"-1\" rad=\"-1\"", ""},
    {"N.m/rad", "kg=\"1\" m=\"2\" s=\"-2\" rad=\"-1\"", ""},
    {"N.m.s/rad", "kg=\"1\" m=\"2\" s=\"-1\" rad=\"-1\"", ""},
    {"Hz", "s=\"-1\"", ""},
    {"V/A", "kg=\"1\" m=\"2\" s=\"-3\" A=\"-2\"", ""},
    {"V/(A.s)", "kg=\"1\" m=\"2\" s=\"-4\" A=\"-2\"", ""},
    {"V/s", "kg=\"1\" m=\"2\" s=\"-4\" A=\"-1\"", ""},
};

const char* to_string(gimbal::Causality c) {
    switch (c) {
        case gimbal::Causality::parameter: return "parameter";
        case gimbal::Causality::input: return "input";
        case gimbal::Causality::output: return "output";
        case gimbal::Causality::local: return "local";
    }
    return "";
}

const char* to_string(gimbal::Variability v) {
    switch (v) {
        case gimbal::Variability::fixed: return "fixed";
        case gimbal::Variability::tunable: return "tunable";
        case gimbal::Variability::discrete: return "discrete";
        case gimbal::Variability::continuous: return "continuous";
    }
    return "";
}

// The shortest decimal that reads back as the same double ("0.1", not "0.10000000000000001").
std::string number(double value) {
    char buffer[40];
    for (int digits = 15; digits <= 17; ++digits) {
        std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
        if (std::strtod(buffer, nullptr) == value) break;
    }
    return buffer;
}

std::string xml_escape(const char* text) {
    std::string out;
    for (const char* c = text; *c != '\0'; ++c) {
        switch (*c) {
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '&': out += "&amp;"; break;
            case '"': out += "&quot;"; break;
            default: out += *c;
        }
    }
    return out;
}

// The switching elements' declarations (gimbal/switching_elements.def), for the texts that name them.
struct ElementText {
    const char* identifier;
    int instances, guards;
    const char* element_switch;
};
constexpr ElementText kElements[] = {
#define ELEMENT(identifier, instances, guards, element_switch, element_class) {#identifier, instances, guards, element_switch},
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
};
struct ModeOutputText {
    const char* element;
    gimbal::IntegerVariable output;
};
constexpr ModeOutputText kModeOutputs[] = {
#define ELEMENT(identifier, instances, guards, element_switch, element_class)
#define MODE_OUTPUT(element, output, lowest, highest) {#element, gimbal::vi_##output},
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
};

// Event indicator k (from 0) in words: its element, instance and guard.
std::string indicator_text(unsigned k) {
    for (const ElementText& element : kElements) {
        const unsigned size = static_cast<unsigned>(element.instances * element.guards);
        if (k < size)
            return std::string(element.identifier) + " " + std::to_string(k / element.guards + 1) + ", its guard " +
                   std::to_string(k % element.guards + 1);
        k -= size;
    }
    return "none";
}

// The Integer outputs that show the elements' modes, with the Boolean parameter that switches each one's
// element on (none: always on), as a tool's annotation: FMI 2.0's <VendorAnnotations><Tool>, FMI 3.0's
// <Annotations><Annotation type>. gimbal2axis records them (FMU.mode_outputs).
std::string vendor_annotations(bool fmi3) {
    std::ostringstream s;
    s << (fmi3 ? "  <Annotations>\n    <Annotation type=\"gimbal2axis\">\n"
               : "  <VendorAnnotations>\n    <Tool name=\"gimbal2axis\">\n")
      << "      <ModeOutputs>\n";
    for (std::size_t m = 0; m < sizeof kModeOutputs / sizeof kModeOutputs[0]; ++m) {
        const ModeOutputText& mode = kModeOutputs[m];
        s << "        <ModeOutput name=\"" << gimbal::kIntegerVariables[mode.output].name << "\" element=\""
          << mode.element << "\"";
        // The instance of this output: how many outputs of its element come before it.
        int instance = 1;
        for (std::size_t k = 0; k < m; ++k)
            if (std::string(kModeOutputs[k].element) == mode.element) ++instance;
        for (const ElementText& element : kElements) {
            if (std::string(element.identifier) != mode.element || element.element_switch[0] == '\0') continue;
            std::string name = element.element_switch;
            const std::size_t at = name.find("<j>");
            if (at != std::string::npos) name.replace(at, 3, std::to_string(instance));
            s << " switch=\"" << name << "\"";
        }
        s << "/>\n";
    }
    s << "      </ModeOutputs>\n" << (fmi3 ? "    </Annotation>\n  </Annotations>\n" : "    </Tool>\n  </VendorAnnotations>\n");
    return s.str();
}

// A file in the same folder as `path`.
std::string beside(const char* path, const char* name) {
    const std::string p(path);
    const std::size_t slash = p.find_last_of('/');
    return (slash == std::string::npos ? std::string() : p.substr(0, slash + 1)) + name;
}

bool write(const char* path, const std::string& text) {
    std::ofstream out(path);
    out << text;
    return static_cast<bool>(out);
}

const UnitDefinition* find_unit(const std::string& name) {
    for (const auto& u : kUnits)
        if (name == u.name) return &u;
    return nullptr;
}

bool is_enumeration_type(const std::string& name) {
    for (const auto& type : gimbal::kEnumerationTypes)
        if (name == type.name) return true;
    return false;
}

bool is_item_value(const std::string& type, double value) {
    for (const auto& item : gimbal::kEnumerationItems)
        if (type == item.type && value == item.value) return true;
    return false;
}

enum class Type { real, integer, boolean };

// The table's rules, beyond what the compiler checks; an empty string when the variable keeps them.
std::string broken_rule(const gimbal::VariableInfo& v, Type type) {
    const std::string unit = v.unit, display_unit = v.display_unit, declared_type = v.declared_type;
    if (type == Type::real) {
        const UnitDefinition* u = find_unit(unit);
        if (u == nullptr) return "uses undefined unit '" + unit + "'";
        if (display_unit != u->display_unit)
            return "must have displayUnit '" + std::string(u->display_unit) + "' (the one of its unit " + unit +
                   "), not '" + display_unit + "'";
    } else if (!unit.empty() || !display_unit.empty()) {
        return "is not Real: it has no unit";
    }
    if (!declared_type.empty()) {
        if (type != Type::integer) return "only Integer variables may be enumerations";
        if (!is_enumeration_type(declared_type)) return "has declaredType '" + declared_type + "', not in enumeration_types.def";
        if (v.min != gimbal::kNoMin || v.max != gimbal::kNoMax) return "an enumeration's items are its bounds: no min or max";
        if (!is_item_value(declared_type, v.start)) return "its start value is no item of " + declared_type;
    }
    if (std::isnan(v.min) || std::isnan(v.max) || v.min > v.max) return "min and max are not an interval";
    if (type == Type::boolean && (v.min != gimbal::kNoMin || v.max != gimbal::kNoMax)) return "a Boolean has no bounds";
    if (type == Type::integer && ((std::isfinite(v.min) && v.min != std::floor(v.min)) ||
                                  (std::isfinite(v.max) && v.max != std::floor(v.max))))
        return "an Integer's bounds are integers";
    if (v.initial != gimbal::Initial::calculated && (v.start < v.min || v.start > v.max))
        return "its start value lies outside [min, max]";
    return "";
}

// 1-based indices of <ModelVariables>: the Real table comes first.
unsigned real_index(gimbal::RealVariable vr) { return vr + 1; }

std::string index_list(const std::vector<unsigned>& indices) {
    std::string list;
    for (unsigned index : indices) list += (list.empty() ? "" : " ") + std::to_string(index);
    return list;
}

// What each continuous output depends on in the continuous-time (Model Exchange) view: the states,
// and the inputs that reach it without passing through a state. (In Co-Simulation the outputs are
// held from step to step; these dependencies are then a superset of the true ones.)
std::vector<unsigned> output_dependencies(gimbal::RealVariable vr) {
    using namespace gimbal;
    std::vector<unsigned> indices;
    for (RealVariable state : kContinuousStates) indices.push_back(real_index(state));
    const auto add = [&indices](const RealVector& vector) {
        for (RealVariable input : vector) indices.push_back(real_index(input));
    };
    switch (vr) {
        // A quasi-static motor's current (its command's in current drive), and the applied voltage.
        case vr_i_R1:
        case vr_amplifier1_u:
            indices.push_back(real_index(vr_u_R1)), indices.push_back(real_index(vr_i_R1_cmd));
            break;
        case vr_i_R2:
        case vr_amplifier2_u:
            indices.push_back(real_index(vr_u_R2)), indices.push_back(real_index(vr_i_R2_cmd));
            break;
        case vr_los_omega_1:
        case vr_los_omega_2:
        case vr_los_omega_3: add(kBaseMotion.attitude), add(kBaseMotion.attitude_rate); break;
        case vr_energy_kinetic: add(kBaseMotion.attitude), add(kBaseMotion.attitude_rate), add(kBaseMotion.velocity_a); break;
        case vr_energy_potential: add(kBaseMotion.attitude); break;
        default: break;
    }
    std::sort(indices.begin(), indices.end());
    return indices;
}

// A derivative of an angle is a rate (of its own body, or N times the load's for a rigid gear); the
// others depend on the whole state and every input.
std::vector<unsigned> derivative_dependencies(int state) {
    using namespace gimbal;
    std::vector<unsigned> indices;
    if (state < 4) {
        for (RealVariable rate : kBodyRate) indices.push_back(real_index(rate));
    } else {
        for (RealVariable s : kContinuousStates) indices.push_back(real_index(s));
        for (unsigned vr = 0; vr < kRealVariableCount; ++vr)
            if (kRealVariables[vr].causality == Causality::input) indices.push_back(real_index(static_cast<RealVariable>(vr)));
    }
    std::sort(indices.begin(), indices.end());
    return indices;
}

std::string bound(double value, Type type) {
    return type == Type::integer ? std::to_string(static_cast<long>(value)) : number(value);
}


// ------------------------------------------------------------------------------------------ FMI 3.0
// The same tables as FMI 3.0 model-description parts. FMI 3 has one value-reference space for all
// types: a Real keeps its value reference, an Integer (Int32 or Enumeration) gets kFmi3IntegerBase +
// its own, a Boolean kFmi3BooleanBase + its own (docs/fmi_interfaces.md). The independent variable,
// which FMI 3.0 requires, is `time` (GIMBAL_FMI3_TIME). The GIMBAL_EVENT_INDICATORS event indicators are
// as many scalar Float64 locals, `event_indicators[1]` .. at GIMBAL_FMI3_FIRST_EVENT_INDICATOR + 0 .., each an
// <EventIndicator> of <ModelStructure>: not one array, because a host without array support reads
// every Float64 as one value (ecos records all variables, locals too, and an array among them made
// each of its reads fail).
// The offsets are gimbal_c_api.h's, which the FMI 3.0 layer adds too.
constexpr unsigned kFmi3IntegerBase = GIMBAL_FMI3_INTEGER_BASE, kFmi3BooleanBase = GIMBAL_FMI3_BOOLEAN_BASE,
                   kFmi3Time = GIMBAL_FMI3_TIME, kFmi3FirstEventIndicator = GIMBAL_FMI3_FIRST_EVENT_INDICATOR;

std::string vr_list(const std::vector<unsigned>& references) {
    std::string list;
    for (unsigned vr : references) list += (list.empty() ? "" : " ") + std::to_string(vr);
    return list;
}

int write_fmi3(char** paths) {
    using namespace gimbal;
    std::ostringstream variables, outputs, derivatives, initial_unknowns;
    struct Table {
        const VariableInfo* variables;
        unsigned count;
        Type type;
        unsigned base;
    };
    const Table tables[] = {{kRealVariables, kRealVariableCount, Type::real, 0},
                            {kIntegerVariables, kIntegerVariableCount, Type::integer, kFmi3IntegerBase},
                            {kBooleanVariables, kBooleanVariableCount, Type::boolean, kFmi3BooleanBase}};
    std::set<std::string> used_units{"s"};
    variables << "    <Float64 name=\"time\" valueReference=\"" << kFmi3Time
              << "\" causality=\"independent\" variability=\"continuous\" description=\"simulation time\" unit=\"s\"/>\n";
    for (const Table& table : tables) {
        for (unsigned index = 0; index < table.count; ++index) {
            const VariableInfo& v = table.variables[index];
            const unsigned vr = table.base + index;
            const bool enumeration = v.declared_type[0] != '\0';
            const char* element = table.type == Type::real ? "Float64"
                                  : table.type == Type::boolean ? "Boolean"
                                  : enumeration ? "Enumeration" : "Int32";
            if (table.type == Type::real) used_units.insert(v.unit);
            variables << "    <" << element << " name=\"" << v.name << "\" valueReference=\"" << vr << "\" causality=\""
                      << to_string(v.causality) << "\" variability=\"" << to_string(v.variability) << "\"";
            if (v.initial == Initial::exact) variables << " initial=\"exact\"";
            if (v.initial == Initial::approx) variables << " initial=\"approx\"";
            if (v.initial == Initial::calculated) variables << " initial=\"calculated\"";
            variables << "\n      description=\"" << xml_escape(v.description) << "\"";
            if (enumeration) variables << " declaredType=\"" << v.declared_type << "\"";
            if (table.type == Type::real) variables << " unit=\"" << v.unit << "\"";
            if (v.display_unit[0] != '\0') variables << " displayUnit=\"" << v.display_unit << "\"";
            if (v.min != kNoMin) variables << " min=\"" << bound(v.min, table.type) << "\"";
            if (v.max != kNoMax) variables << " max=\"" << bound(v.max, table.type) << "\"";
            for (int k = 0; k < kContinuousStateCount; ++k)
                if (table.type == Type::real && index == kStateDerivatives[k])
                    variables << " derivative=\"" << kContinuousStates[k] << "\"";
            if (v.initial != Initial::calculated) {
                if (table.type == Type::boolean) variables << " start=\"" << (v.start != 0.0 ? "true" : "false") << "\"";
                else if (table.type == Type::real) variables << " start=\"" << number(v.start) << "\"";
                else variables << " start=\"" << static_cast<long>(v.start) << "\"";
            }
            variables << "/>\n";
            if (v.causality == Causality::output) {
                std::vector<unsigned> dependencies;
                if (table.type == Type::real && index != vr_events_last_time)
                    for (unsigned i : output_dependencies(static_cast<RealVariable>(index))) dependencies.push_back(i - 1);
                outputs << "    <Output valueReference=\"" << vr << "\" dependencies=\"" << vr_list(dependencies) << "\"/>\n";
            }
            // Computed in Initialization Mode: the calculated outputs, and the approx ones (the rotors).
            if ((v.causality == Causality::output || v.causality == Causality::local) &&
                (v.initial == Initial::calculated || v.initial == Initial::approx))
                initial_unknowns << "    <InitialUnknown valueReference=\"" << vr << "\"/>\n";
        }
    }
    std::ostringstream event_indicators;
    for (unsigned k = 0; k < GIMBAL_EVENT_INDICATORS; ++k) {
        const unsigned vr = kFmi3FirstEventIndicator + k;
        variables << "    <Float64 name=\"event_indicators[" << k + 1 << "]\" valueReference=\"" << vr
                  << "\" causality=\"local\" variability=\"continuous\" initial=\"calculated\"\n"
                  << "      description=\"guard " << k + 1 << " of the switching elements (docs/model_exchange.md): "
                  << indicator_text(k) << "; constant 1 where the fidelity has no such element, and in Co-Simulation\"/>\n";
        event_indicators << "    <EventIndicator valueReference=\"" << vr << "\"/>\n";
    }
    for (int k = 0; k < kContinuousStateCount; ++k) {
        std::vector<unsigned> dependencies;
        for (unsigned i : derivative_dependencies(k)) dependencies.push_back(i - 1);
        derivatives << "    <ContinuousStateDerivative valueReference=\"" << kStateDerivatives[k] << "\" dependencies=\""
                    << vr_list(dependencies) << "\"/>\n";
    }
    std::ostringstream units;
    for (const auto& u : kUnits) {
        if (used_units.count(u.name) == 0) continue;
        units << "    <Unit name=\"" << u.name << "\">";
        if (u.base_unit[0] != '\0') units << "<BaseUnit " << u.base_unit << "/>";
        if (u.display_unit[0] != '\0')
            units << "<DisplayUnit name=\"" << u.display_unit << "\" factor=\"" << kDegreesPerRadian << "\"/>";
        units << "</Unit>\n";
    }
    std::ostringstream types;
    types << "  <TypeDefinitions>\n";
    for (const auto& type : kEnumerationTypes) {
        types << "    <EnumerationType name=\"" << type.name << "\" description=\"" << xml_escape(type.description) << "\">\n";
        for (const auto& item : kEnumerationItems) {
            if (std::string(item.type) != type.name) continue;
            types << "      <Item name=\"" << item.name << "\" value=\"" << item.value << "\" description=\""
                  << xml_escape(item.description) << "\"/>\n";
        }
        types << "    </EnumerationType>\n";
    }
    types << "  </TypeDefinitions>\n";
    std::ostringstream structure;
    structure << outputs.str() << derivatives.str() << initial_unknowns.str() << event_indicators.str();
    const std::string tolerance = number(kRealVariables[vr_solver_rtol].start);
    return write(paths[0], units.str()) && write(paths[1], variables.str()) && write(paths[2], structure.str()) &&
                   write(paths[3], types.str()) && write(paths[4], tolerance) &&
                   write(beside(paths[4], "event_indicators.txt").c_str(), std::to_string(GIMBAL_EVENT_INDICATORS)) &&
                   write(beside(paths[4], "vendor_annotations.xml").c_str(), vendor_annotations(true))
               ? 0
               : 1;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc == 7 && std::string(argv[1]) == "--fmi3") return write_fmi3(argv + 2);
    if (argc != 6) {
        std::cerr << "usage: " << argv[0]
                  << " <units.xml> <variables.xml> <structure.xml> <types.xml> <default_tolerance.txt>\n";
        return 2;
    }
    std::set<std::string> used_units;

    std::ostringstream variables, outputs, initial_unknowns;
    unsigned index = 0;
    struct Table {
        const gimbal::VariableInfo* variables;
        unsigned count;
        Type type;
        const char* element;
    };
    const Table tables[] = {{gimbal::kRealVariables, gimbal::kRealVariableCount, Type::real, "Real"},
                            {gimbal::kIntegerVariables, gimbal::kIntegerVariableCount, Type::integer, "Integer"},
                            {gimbal::kBooleanVariables, gimbal::kBooleanVariableCount, Type::boolean, "Boolean"}};
    for (const Table& table : tables) {
        for (unsigned vr = 0; vr < table.count; ++vr) {
            const gimbal::VariableInfo& v = table.variables[vr];
            ++index;
            const std::string rule = broken_rule(v, table.type);
            if (!rule.empty()) {
                std::cerr << "variable " << v.name << ": " << rule << "\n";
                return 1;
            }
            const bool enumeration = v.declared_type[0] != '\0';
            if (table.type == Type::real) used_units.insert(v.unit);
            variables << "    <!-- index " << index << " -->\n"
                      << "    <ScalarVariable name=\"" << v.name << "\" valueReference=\"" << vr << "\" causality=\""
                      << to_string(v.causality) << "\" variability=\"" << to_string(v.variability) << "\"";
            if (v.initial == gimbal::Initial::exact) variables << " initial=\"exact\"";
            if (v.initial == gimbal::Initial::approx) variables << " initial=\"approx\"";
            if (v.initial == gimbal::Initial::calculated) variables << " initial=\"calculated\"";
            variables << "\n      description=\"" << xml_escape(v.description) << "\">\n      <"
                      << (enumeration ? "Enumeration" : table.element);
            if (enumeration) variables << " declaredType=\"" << v.declared_type << "\"";
            if (table.type == Type::real) variables << " unit=\"" << v.unit << "\"";
            if (v.display_unit[0] != '\0') variables << " displayUnit=\"" << v.display_unit << "\"";
            if (v.min != gimbal::kNoMin) variables << " min=\"" << bound(v.min, table.type) << "\"";
            if (v.max != gimbal::kNoMax) variables << " max=\"" << bound(v.max, table.type) << "\"";
            for (int k = 0; k < gimbal::kContinuousStateCount; ++k)
                if (table.type == Type::real && vr == gimbal::kStateDerivatives[k])
                    variables << " derivative=\"" << real_index(gimbal::kContinuousStates[k]) << "\"";
            if (v.initial != gimbal::Initial::calculated) {
                if (table.type == Type::boolean) variables << " start=\"" << (v.start != 0.0 ? "true" : "false") << "\"";
                else if (table.type == Type::real) variables << " start=\"" << number(v.start) << "\"";
                else variables << " start=\"" << static_cast<long>(v.start) << "\"";
            }
            variables << "/>\n    </ScalarVariable>\n";
            const bool continuous_output = table.type == Type::real && v.causality == gimbal::Causality::output &&
                                           vr != gimbal::vr_events_last_time;
            if (continuous_output) {
                outputs << "      <Unknown index=\"" << index << "\" dependencies=\""
                        << index_list(output_dependencies(static_cast<gimbal::RealVariable>(vr))) << "\"/>\n";
            } else if (v.causality == gimbal::Causality::output) {
                // Event counters, modes and the last event's time change at events only.
                outputs << "      <Unknown index=\"" << index << "\" dependencies=\"\"/>\n";
            }
            // Computed in Initialization Mode: the calculated outputs, and the approx ones (the rotors).
            if ((v.causality == gimbal::Causality::output || v.causality == gimbal::Causality::local) &&
                (v.initial == gimbal::Initial::calculated || v.initial == gimbal::Initial::approx))
                initial_unknowns << "      <Unknown index=\"" << index << "\"/>\n";
        }
    }

    std::ostringstream units;
    for (const auto& u : kUnits) {
        if (used_units.count(u.name) == 0) continue;
        units << "    <Unit name=\"" << u.name << "\">";
        if (u.base_unit[0] != '\0') units << "<BaseUnit " << u.base_unit << "/>";
        if (u.display_unit[0] != '\0')
            units << "<DisplayUnit name=\"" << u.display_unit << "\" factor=\"" << kDegreesPerRadian << "\" offset=\"0\"/>";
        units << "</Unit>\n";
    }

    std::ostringstream types;
    types << "  <TypeDefinitions>\n";
    for (const auto& type : gimbal::kEnumerationTypes) {
        types << "    <SimpleType name=\"" << type.name << "\" description=\"" << xml_escape(type.description)
              << "\">\n      <Enumeration>\n";
        for (const auto& item : gimbal::kEnumerationItems) {
            if (std::string(item.type) != type.name) continue;
            types << "        <Item name=\"" << item.name << "\" value=\"" << item.value << "\" description=\""
                  << xml_escape(item.description) << "\"/>\n";
        }
        types << "      </Enumeration>\n    </SimpleType>\n";
    }
    types << "  </TypeDefinitions>\n";

    std::ostringstream structure;
    std::ostringstream derivatives;
    for (int k = 0; k < gimbal::kContinuousStateCount; ++k)
        derivatives << "      <Unknown index=\"" << real_index(gimbal::kStateDerivatives[k]) << "\" dependencies=\""
                    << index_list(derivative_dependencies(k)) << "\"/>\n";
    structure << "    <Outputs>\n" << outputs.str() << "    </Outputs>\n"
              << "    <Derivatives>\n" << derivatives.str() << "    </Derivatives>\n"
              << "    <InitialUnknowns>\n" << initial_unknowns.str() << "    </InitialUnknowns>\n";
    const std::string tolerance = number(gimbal::kRealVariables[gimbal::vr_solver_rtol].start);
    return write(argv[1], units.str()) && write(argv[2], variables.str()) && write(argv[3], structure.str()) &&
                   write(argv[4], types.str()) && write(argv[5], tolerance) &&
                   write(beside(argv[5], "event_indicators.txt").c_str(), std::to_string(GIMBAL_EVENT_INDICATORS)) &&
                   write(beside(argv[5], "vendor_annotations.xml").c_str(), vendor_annotations(false))
               ? 0
               : 1;
}
