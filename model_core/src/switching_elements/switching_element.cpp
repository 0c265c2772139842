#include "gimbal/switching_elements/switching_element.hpp"

namespace gimbal {

int SwitchingElement::side(double value, const int* crossings, int guard) const {
    const int crossed = crossing(crossings, guard);
    return crossed != 0 ? crossed : switching::sign(value);
}

namespace switching {

int select_contact(bool at_plus_stop, bool at_minus_stop, int pull_sign, int current) {
    if (at_plus_stop && (pull_sign > 0 || (pull_sign == 0 && current == 1))) return 1;
    if (at_minus_stop && (pull_sign < 0 || (pull_sign == 0 && current == -1))) return -1;
    return 0;
}

std::string transition(const char* from, const char* to) { return std::string(from) + " -> " + to; }

}  // namespace switching
}  // namespace gimbal
