// Linux input event codes by name (linux/input-event-codes.h), for the robot file's gamepad
// mapping (transports of kind evdev): the absolute axes and the buttons a gamepad or joystick
// reports. Data only; the transport that reads a device is runtime/transport/evdev.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace pbppo::robot {

enum class InputCodeKind : std::uint8_t { kAxis, kButton };

// The code of `name` ("ABS_Y", "BTN_SOUTH", aliases such as "BTN_A" included) of that kind; -1:
// not one of them.
int InputCode(InputCodeKind kind, std::string_view name) noexcept;
// The name of `code` of that kind ("ABS_Y"; the first of its aliases); nullptr: not one of them.
const char* InputCodeName(InputCodeKind kind, int code) noexcept;
// The names of that kind, comma-separated (for errors).
std::string InputCodeNames(InputCodeKind kind);

}  // namespace pbppo::robot
