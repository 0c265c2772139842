// Writes the parts of modelDescription.xml that follow from the variable table, so that the names,
// value references, units and start values the FMU serves can never drift from what it declares.
// Usage: gimbal_model_description_generator <units.xml> <variables.xml> <structure.xml>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>

#include "gimbal/variables.hpp"

namespace {

struct UnitDefinition {
    const char* name;
    const char* base_unit;  // attributes of <BaseUnit>
    const char* display;    // extra <DisplayUnit> elements
};

const UnitDefinition kUnits[] = {
    {"1", "", ""},
    {"rad", "rad=\"1\"", "<DisplayUnit name=\"deg\" factor=\"57.29577951308232\"/>"},
    {"rad/s", "s=\"-1\" rad=\"1\"", "<DisplayUnit name=\"deg/s\" factor=\"57.29577951308232\"/>"},
    {"rad/s2", "s=\"-2\" rad=\"1\"", "<DisplayUnit name=\"deg/s2\" factor=\"57.29577951308232\"/>"},
    {"s", "s=\"1\"", ""},
    {"m", "m=\"1\"", ""},
    {"m/s", "m=\"1\" s=\"-1\"", ""},
    {"m/s2", "m=\"1\" s=\"-2\"", ""},
    {"kg", "kg=\"1\"", ""},
    {"kg.m2", "kg=\"1\" m=\"2\"", ""},
    {"V", "kg=\"1\" m=\"2\" s=\"-3\" A=\"-1\"", ""},
    {"A", "A=\"1\"", ""},
    {"Ohm", "kg=\"1\" m=\"2\" s=\"-3\" A=\"-2\"", ""},
    {"H", "kg=\"1\" m=\"2\" s=\"-2\" A=\"-2\"", ""},
    {"N.m", "kg=\"1\" m=\"2\" s=\"-2\"", ""},
    {"J", "kg=\"1\" m=\"2\" s=\"-2\"", ""},
    {"N.m/A", "kg=\"1\" m=\"2\" s=\"-2\" A=\"-1\"", ""},
    {"V.s/rad", "kg=\"1\" m=\"2\" s=\"-2\" A=\"-1\" rad=\"-1\"", ""},
    {"N.m/rad", "kg=\"1\" m=\"2\" s=\"-2\" rad=\"-1\"", ""},
    {"N.m.s/rad", "kg=\"1\" m=\"2\" s=\"-1\" rad=\"-1\"", ""},
};

const char* to_string(gimbal::Causality c) {
    switch (c) {
        case gimbal::Causality::parameter: return "parameter";
        case gimbal::Causality::input: return "input";
        case gimbal::Causality::output: return "output";
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

std::string number(double value) {
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "%.17g", value);
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

bool write(const char* path, const std::string& text) {
    std::ofstream out(path);
    out << text;
    return static_cast<bool>(out);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 4) {
        std::cerr << "usage: " << argv[0] << " <units.xml> <variables.xml> <structure.xml>\n";
        return 2;
    }
    std::set<std::string> used_units, known_units;
    for (const auto& u : kUnits) known_units.insert(u.name);

    std::ostringstream variables, outputs, initial_unknowns;
    unsigned index = 0;
    struct Table {
        const gimbal::VariableInfo* variables;
        unsigned count;
        const char* type;
    };
    const Table tables[] = {{gimbal::kRealVariables, gimbal::kRealVariableCount, "Real"},
                            {gimbal::kIntegerVariables, gimbal::kIntegerVariableCount, "Integer"},
                            {gimbal::kBooleanVariables, gimbal::kBooleanVariableCount, "Boolean"}};
    for (const Table& table : tables) {
        const bool real = std::string(table.type) == "Real";
        for (unsigned vr = 0; vr < table.count; ++vr) {
            const gimbal::VariableInfo& v = table.variables[vr];
            ++index;
            if (real && known_units.count(v.unit) == 0) {
                std::cerr << "variable " << v.name << " uses undefined unit " << v.unit << "\n";
                return 1;
            }
            if (real) used_units.insert(v.unit);
            variables << "    <!-- index " << index << " -->\n"
                      << "    <ScalarVariable name=\"" << v.name << "\" valueReference=\"" << vr << "\" causality=\""
                      << to_string(v.causality) << "\" variability=\"" << to_string(v.variability) << "\"";
            if (v.initial == gimbal::Initial::exact) variables << " initial=\"exact\"";
            if (v.initial == gimbal::Initial::calculated) variables << " initial=\"calculated\"";
            variables << "\n      description=\"" << xml_escape(v.description) << "\">\n      <" << table.type;
            if (real) variables << " unit=\"" << v.unit << "\"";
            if (v.display_unit[0] != '\0') variables << " displayUnit=\"" << v.display_unit << "\"";
            if (v.initial != gimbal::Initial::calculated) {
                if (std::string(table.type) == "Boolean") variables << " start=\"" << (v.start != 0.0 ? "true" : "false") << "\"";
                else if (real) variables << " start=\"" << number(v.start) << "\"";
                else variables << " start=\"" << static_cast<long>(v.start) << "\"";
            }
            variables << "/>\n    </ScalarVariable>\n";
            if (v.causality == gimbal::Causality::output) {
                // Outputs are computed in fmi2DoStep: setting an input changes none before the next step.
                outputs << "      <Unknown index=\"" << index << "\" dependencies=\"\"/>\n";
                if (v.initial == gimbal::Initial::calculated)
                    initial_unknowns << "      <Unknown index=\"" << index << "\"/>\n";
            }
        }
    }

    std::ostringstream units;
    for (const auto& u : kUnits) {
        if (used_units.count(u.name) == 0) continue;
        units << "    <Unit name=\"" << u.name << "\">";
        if (u.base_unit[0] != '\0') units << "<BaseUnit " << u.base_unit << "/>";
        units << u.display << "</Unit>\n";
    }
    std::ostringstream structure;
    structure << "    <Outputs>\n" << outputs.str() << "    </Outputs>\n"
              << "    <InitialUnknowns>\n" << initial_unknowns.str() << "    </InitialUnknowns>\n";
    return write(argv[1], units.str()) && write(argv[2], variables.str()) && write(argv[3], structure.str()) ? 0 : 1;
}
