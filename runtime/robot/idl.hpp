// The one reader of IDL (OMG IDL 4, the subset that robots' DDS message files use): a robot's
// messages are declared once, in its IDL files under models/<robot>/idl/, and read at set-up into
// a flat list of leaves (one per primitive) that says where each sits on the wire. The DDS
// transport encodes and decodes samples from it (runtime/transport/dds/cdr.hpp); robot.yaml maps
// the leaves onto the robot's fields and commands. Set-up time only.
//
// Read: modules; structs (final extensibility, the default of plain CDR; a forward declaration
// is fine); members of the primitive types (boolean, char, octet, short, long, long long and
// their unsigned forms, the IDL 4 int8 ... uint64, float, double), enums (32 bits), nested
// structs and typedefs of them, fixed arrays of any of them in any number of dimensions, sized by
// literals or integer constants; strings (string, string<N>: skipped, their text is not read) and
// sequences of primitives (sequence<T>, sequence<T, N>: ROS 2's float32[] and int32[], as in
// sensor_msgs/Joy); comments; #include "file" (resolved beside the including file, each file
// once), include guards and #pragma lines. Refused with the file, line and member named:
// sequences of structs, strings or sequences, maps, unions, long double, wchar, @key, @optional,
// @external and appendable or mutable extensibility.
//
// A message with strings or sequences has a layout of its own (IdlMessage::items): each sequence
// with as many elements as the robot file names (IdlMessage::Element grows it), each string empty.
// Samples are held in that layout, one size, so that the tick converts them without allocation; a
// received sample is rewritten into it (runtime/transport/dds/cdr.hpp), and one whose sequence is
// shorter than the layout's is refused as malformed.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::robot {

enum class IdlScalar : std::uint8_t {
  kBool,
  kChar,
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kInt64,
  kUint64,
  kFloat,
  kDouble
};
// Its size in bytes (1, 2, 4 or 8).
std::uint32_t IdlScalarSize(IdlScalar type) noexcept;
// A counter's range as a mask (uint8 0xff, uint16 0xffff, uint32 0xffffffff): what a field mapped
// as "increase(LEAF)" may read; 0 for every other type.
std::uint32_t IdlCounterMask(IdlScalar type) noexcept;
// The IDL 4 spelling (boolean, char, int8 ... uint64, float, double).
const char* ToString(IdlScalar type) noexcept;

// One primitive of a message: its path ("x_m", "sonar_m[3]", "motor_state[2].q"), its type, and
// where it sits in the message's CDR encoding (plain XCDR1 as Fast DDS and Cyclone DDS write
// final structs: the data after the 4-byte encapsulation header, each primitive aligned to its
// size) and in the message as a C struct with natural alignment (what a device's checksum over
// its own memory layout covers).
struct IdlLeaf {
  std::string path;
  IdlScalar type = IdlScalar::kDouble;
  std::uint32_t cdr_offset = 0;
  std::uint32_t c_offset = 0;
};

// A member of a message with strings or sequences, in wire order: a primitive (one leaf), a
// string (a 4-byte length with its terminating NUL, then the characters) or a sequence (a 4-byte
// count, then the elements, of which the layout holds `elements`).
struct IdlItem {
  enum class Kind : std::uint8_t { kLeaf, kString, kSequence };
  Kind kind = Kind::kLeaf;
  std::uint32_t leaf = 0;                 // kLeaf
  std::string path;                       // kString, kSequence: the member ("header.frame_id", "axes")
  IdlScalar element = IdlScalar::kFloat;  // kSequence
  std::uint32_t bound = 0;                // kString, kSequence: the largest length; 0 unbounded
  std::uint32_t cdr_offset = 0;           // kString, kSequence: where its length is in the layout
  std::vector<std::uint32_t> elements;    // kSequence: the leaves of the layout's elements, in order
};

struct IdlMessage {
  std::string type_name;  // qualified: pbppo_idl::auv::SensorState
  std::string file;       // the file it was declared in
  std::vector<IdlLeaf> leaves;
  std::uint32_t cdr_size = 0;  // bytes of CDR data (without the encapsulation header)
  std::uint32_t c_size = 0;    // the C struct's size, padded to its alignment (0: strings or sequences)
  // Empty for a message of fixed size (leaves in wire order); otherwise its members in wire order
  // (a sequence's element leaves are added at the end of `leaves` as Element names them).
  std::vector<IdlItem> items;

  bool variable() const noexcept { return !items.empty(); }
  // The leaf at `path`; -1 when there is none.
  int LeafIndex(std::string_view path) const noexcept;
  // The same, and for an element of a sequence the layout does not hold yet ("axes[7]"), the
  // layout grows to hold the sequence's elements up to it (leaves added, offsets laid out again).
  // -1 when there is none, the index is past the sequence's bound, or the layout would exceed the
  // limits of ParseIdlMessage. Set-up time.
  int Element(std::string_view path);
};

// Reads an included file by the path the include resolved to (relative paths joined to the
// including file's folder); set-up time.
using IdlFileReader = std::function<Result<std::string>(const std::string& path)>;

// Parses the IDL `text` of file `path` (includes read through `read`) and flattens the struct
// `type_name` (qualified with "::", a leading "::" optional; empty: the last struct the file
// itself defines). Limits: 65,536 bytes of CDR data, 16,384 leaves, arrays of 65,536 elements,
// 16 levels of nesting and of includes; beyond them the error names the member and the limit.
Result<IdlMessage> ParseIdlMessage(const std::string& text, const std::string& path, const std::string& type_name,
                                   const IdlFileReader& read);

}  // namespace pbppo::robot
