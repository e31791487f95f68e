#include "runtime/robot/input_codes.hpp"

#include <linux/input-event-codes.h>

namespace pbppo::robot {
namespace {

struct Named {
  const char* name;
  int code;
};

constexpr Named kAxes[] = {
    {"ABS_X", ABS_X},
    {"ABS_Y", ABS_Y},
    {"ABS_Z", ABS_Z},
    {"ABS_RX", ABS_RX},
    {"ABS_RY", ABS_RY},
    {"ABS_RZ", ABS_RZ},
    {"ABS_THROTTLE", ABS_THROTTLE},
    {"ABS_RUDDER", ABS_RUDDER},
    {"ABS_WHEEL", ABS_WHEEL},
    {"ABS_GAS", ABS_GAS},
    {"ABS_BRAKE", ABS_BRAKE},
    {"ABS_HAT0X", ABS_HAT0X},
    {"ABS_HAT0Y", ABS_HAT0Y},
    {"ABS_HAT1X", ABS_HAT1X},
    {"ABS_HAT1Y", ABS_HAT1Y},
    {"ABS_HAT2X", ABS_HAT2X},
    {"ABS_HAT2Y", ABS_HAT2Y},
    {"ABS_HAT3X", ABS_HAT3X},
    {"ABS_HAT3Y", ABS_HAT3Y},
};

constexpr Named kButtons[] = {
    {"BTN_SOUTH", BTN_SOUTH},
    {"BTN_A", BTN_A},
    {"BTN_EAST", BTN_EAST},
    {"BTN_B", BTN_B},
    {"BTN_C", BTN_C},
    {"BTN_NORTH", BTN_NORTH},
    {"BTN_X", BTN_X},
    {"BTN_WEST", BTN_WEST},
    {"BTN_Y", BTN_Y},
    {"BTN_Z", BTN_Z},
    {"BTN_TL", BTN_TL},
    {"BTN_TR", BTN_TR},
    {"BTN_TL2", BTN_TL2},
    {"BTN_TR2", BTN_TR2},
    {"BTN_SELECT", BTN_SELECT},
    {"BTN_START", BTN_START},
    {"BTN_MODE", BTN_MODE},
    {"BTN_THUMBL", BTN_THUMBL},
    {"BTN_THUMBR", BTN_THUMBR},
    {"BTN_TRIGGER", BTN_TRIGGER},
    {"BTN_THUMB", BTN_THUMB},
    {"BTN_THUMB2", BTN_THUMB2},
    {"BTN_TOP", BTN_TOP},
    {"BTN_TOP2", BTN_TOP2},
    {"BTN_PINKIE", BTN_PINKIE},
    {"BTN_BASE", BTN_BASE},
    {"BTN_BASE2", BTN_BASE2},
    {"BTN_BASE3", BTN_BASE3},
    {"BTN_BASE4", BTN_BASE4},
    {"BTN_BASE5", BTN_BASE5},
    {"BTN_BASE6", BTN_BASE6},
    {"BTN_DPAD_UP", BTN_DPAD_UP},
    {"BTN_DPAD_DOWN", BTN_DPAD_DOWN},
    {"BTN_DPAD_LEFT", BTN_DPAD_LEFT},
    {"BTN_DPAD_RIGHT", BTN_DPAD_RIGHT},
};

template <std::size_t N>
int Find(const Named (&table)[N], std::string_view name) noexcept {
  for (const Named& n : table)
    if (name == n.name) return n.code;
  return -1;
}

template <std::size_t N>
const char* NameOf(const Named (&table)[N], int code) noexcept {
  for (const Named& n : table)
    if (n.code == code) return n.name;
  return nullptr;
}

template <std::size_t N>
std::string Names(const Named (&table)[N]) {
  std::string s;
  for (const Named& n : table) s += (s.empty() ? "" : ", ") + std::string(n.name);
  return s;
}

}  // namespace

int InputCode(InputCodeKind kind, std::string_view name) noexcept {
  return kind == InputCodeKind::kAxis ? Find(kAxes, name) : Find(kButtons, name);
}

const char* InputCodeName(InputCodeKind kind, int code) noexcept {
  return kind == InputCodeKind::kAxis ? NameOf(kAxes, code) : NameOf(kButtons, code);
}

std::string InputCodeNames(InputCodeKind kind) {
  return kind == InputCodeKind::kAxis ? Names(kAxes) : Names(kButtons);
}

}  // namespace pbppo::robot
