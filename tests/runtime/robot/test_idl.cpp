// The IDL reader: messages flattened into leaves with their CDR and C offsets (the C offsets
// checked against the compiler's own layout of the same struct), includes, typedefs, constants,
// enums and nested struct arrays as robots' message files use them, and every refused construct
// named with its file and line.
#include <doctest/doctest.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

#include "runtime/robot/idl.hpp"

using namespace pbppo;
using namespace pbppo::robot;

namespace {

// Files by path, for #include.
struct Files {
  std::map<std::string, std::string> text;
  IdlFileReader reader() const {
    return [this](const std::string& path) -> Result<std::string> {
      const auto it = text.find(path);
      if (it == text.end()) return MakeError(ErrorCode::kIo, "'" + path + "' cannot be read");
      return it->second;
    };
  }
};

Result<IdlMessage> Parse(const std::string& text, const std::string& type = "", const Files& files = {}) {
  return ParseIdlMessage(text, "dir/msg.idl", type, files.reader());
}

IdlMessage Ok(const std::string& text, const std::string& type = "", const Files& files = {}) {
  auto m = Parse(text, type, files);
  REQUIRE_MESSAGE(m.ok(), (m.ok() ? "" : m.error().message));
  return std::move(*m);
}

std::string Refusal(const std::string& text, const std::string& type = "", const Files& files = {}) {
  auto m = Parse(text, type, files);
  REQUIRE_FALSE(m.ok());
  return m.error().message;
}

const IdlLeaf& Leaf(const IdlMessage& m, const std::string& path) {
  const int k = m.LeafIndex(path);
  REQUIRE_MESSAGE(k >= 0, path);
  return m.leaves[static_cast<std::size_t>(k)];
}

// The same layout as the IDL below, laid out by the compiler: its offsets are the C offsets.
struct Motor {
  std::uint8_t mode;
  float q, dq;
  std::uint8_t temperature;
  std::uint32_t lost;
  std::uint32_t reserve[2];
};
struct Imu {
  float quaternion[4];
  std::int16_t raw[2][3];
  std::uint8_t temperature;
};
struct State {
  std::uint8_t head[2];
  std::uint8_t level_flag;
  std::uint32_t sn[2];
  Imu imu;
  Motor motor[3];
  std::int64_t stamp;
  bool ok;
  std::uint32_t mode;  // an enum
  double tail;
  std::uint32_t crc;
};

const char* kMotorIdl = R"(
#ifndef MOTOR_IDL
#define MOTOR_IDL
module robot { module msg {
  @final struct Motor_ {
    octet mode;
    float q, dq;   // two declarators
    uint8 temperature;
    unsigned long lost;
    unsigned long reserve[2];
  };
}; };
#endif
)";

const char* kStateIdl = R"(
#include "Motor_.idl"
#pragma some_vendor thing
/* a block comment
   over lines */
module robot {
  const long kMotors = 3;
  module msg {
    typedef short Raw[3];
    enum Mode { kOff, kOn, @value(7) kFault };
    struct Imu_ {
      float quaternion[4];
      Raw raw[2];
      octet temperature;
    };
    @extensibility(FINAL) struct State_ {
      octet head[2];
      octet level_flag;
      unsigned long sn[2];
      Imu_ imu;
      Motor_ motor[kMotors];
      long long stamp;
      boolean ok;
      Mode mode;
      double tail;
      unsigned long crc;
    };
  };
};
)";

}  // namespace

TEST_CASE("idl: nested structs, arrays, typedefs, constants and enums flatten into leaves at their C offsets") {
  Files files;
  files.text["dir/Motor_.idl"] = kMotorIdl;
  const IdlMessage m = Ok(kStateIdl, "", files);
  CHECK(m.type_name == "robot::msg::State_");
  CHECK(m.file == "dir/msg.idl");
  // 2 + 1 + 2 + (4 + 6 + 1) + 3 * 7 + 5 leaves.
  CHECK(m.leaves.size() == 2 + 1 + 2 + 11 + 21 + 5);
  CHECK(m.c_size == sizeof(State));
  CHECK(Leaf(m, "head[1]").c_offset == offsetof(State, head) + 1);
  CHECK(Leaf(m, "sn[1]").c_offset == offsetof(State, sn) + 4);
  CHECK(Leaf(m, "imu.quaternion[3]").c_offset == offsetof(State, imu) + offsetof(Imu, quaternion) + 12);
  CHECK(Leaf(m, "imu.raw[1][2]").c_offset == offsetof(State, imu) + offsetof(Imu, raw) + 5 * 2);
  CHECK(Leaf(m, "imu.raw[1][2]").type == IdlScalar::kInt16);
  CHECK(Leaf(m, "imu.temperature").c_offset == offsetof(State, imu) + offsetof(Imu, temperature));
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string p = "motor[" + std::to_string(k) + "].";
    const std::size_t base = offsetof(State, motor) + k * sizeof(Motor);
    CHECK(Leaf(m, p + "mode").c_offset == base + offsetof(Motor, mode));
    CHECK(Leaf(m, p + "dq").c_offset == base + offsetof(Motor, dq));
    CHECK(Leaf(m, p + "lost").c_offset == base + offsetof(Motor, lost));
    CHECK(Leaf(m, p + "reserve[1]").c_offset == base + offsetof(Motor, reserve) + 4);
  }
  CHECK(Leaf(m, "stamp").c_offset == offsetof(State, stamp));
  CHECK(Leaf(m, "ok").c_offset == offsetof(State, ok));
  CHECK(Leaf(m, "mode").type == IdlScalar::kUint32);
  CHECK(Leaf(m, "mode").c_offset == offsetof(State, mode));
  CHECK(Leaf(m, "tail").c_offset == offsetof(State, tail));
  CHECK(Leaf(m, "crc").c_offset == offsetof(State, crc));
  // CDR: each primitive aligned to its own size from the start of the data, no padding between
  // structs: the motors' floats follow their octets at the next multiple of 4.
  for (const IdlLeaf& l : m.leaves) CHECK(l.cdr_offset % IdlScalarSize(l.type) == 0);
  CHECK(Leaf(m, "head[0]").cdr_offset == 0);
  CHECK(Leaf(m, "level_flag").cdr_offset == 2);
  CHECK(Leaf(m, "sn[0]").cdr_offset == 4);
  CHECK(Leaf(m, "imu.quaternion[0]").cdr_offset == 12);
  CHECK(Leaf(m, "imu.raw[0][0]").cdr_offset == 28);
  CHECK(Leaf(m, "imu.temperature").cdr_offset == 40);
  CHECK(Leaf(m, "motor[0].mode").cdr_offset == 41);
  CHECK(Leaf(m, "motor[0].q").cdr_offset == 44);
  CHECK(Leaf(m, "motor[0].temperature").cdr_offset == 52);
  CHECK(Leaf(m, "motor[0].lost").cdr_offset == 56);
  CHECK(Leaf(m, "motor[1].mode").cdr_offset == 68);
  CHECK(Leaf(m, "stamp").cdr_offset == 128);  // after motor[2] (96..124), aligned to 8
  CHECK(m.cdr_size == Leaf(m, "crc").cdr_offset + 4);
  // Another struct of the files by name, relative or absolute.
  CHECK(Ok(kStateIdl, "robot::msg::Motor_", files).leaves.size() == 7);
  CHECK(Ok(kStateIdl, "::robot::msg::Imu_", files).leaves.size() == 11);
}

TEST_CASE("idl: the shipped messages' primitive spellings and the default struct") {
  const IdlMessage m = Ok(R"(module a { struct First { double x; };
    struct Cmd { unsigned long long tick; long long stamp; unsigned short u16; short i16; long i32; char c;
                 int8 i8; uint64 big; float f; boolean b; }; };)");
  CHECK(m.type_name == "a::Cmd");  // the file's last struct
  const IdlScalar want[] = {IdlScalar::kUint64, IdlScalar::kInt64, IdlScalar::kUint16, IdlScalar::kInt16,
                            IdlScalar::kInt32,  IdlScalar::kChar,  IdlScalar::kInt8,   IdlScalar::kUint64,
                            IdlScalar::kFloat,  IdlScalar::kBool};
  REQUIRE(m.leaves.size() == 10);
  for (std::size_t i = 0; i < 10; ++i) CHECK(m.leaves[i].type == want[i]);
  // A struct only included is not the default: the including file's own last one is.
  Files files;
  files.text["dir/b.idl"] = "module b { struct Late { octet o; }; };";
  CHECK(Ok("#include \"b.idl\"\nmodule a { struct Mine { b::Late l; }; };", "", files).type_name == "a::Mine");
}

TEST_CASE("idl: what a message cannot be is refused naming the file, the line and the construct") {
  const struct {
    const char* text;
    const char* want;
  } cases[] = {
      {"struct T { double v; };\nstruct S {\n sequence<T> v; };",
       "msg.idl:3: sequence<T>: only sequences of primitives"},
      {"struct S { sequence<string> v; };", "sequence<string>: only sequences of primitives"},
      {"struct S { sequence<sequence<float> > v; };", "only sequences of primitives"},
      {"struct S { sequence<float, 0> v; };", "sequence bounded to 0"},
      {"struct S { string<0> v; };", "string bounded to 0"},
      {"struct S { sequence<float v; };", "expected '>'"},
      {"struct S { wstring name; };", "wstring is not supported"},
      {"struct S { map<long, long> m; };", "map is not supported"},
      {"struct S { string names[20000]; };", "msg.idl:1: member 'names': the message exceeds 65536 bytes"},
      {"struct S { @key long id; double v; };", "@key: not supported"},
      {"@appendable struct S { double v; };", "@appendable: only final structs"},
      {"@extensibility(MUTABLE) struct S { double v; };", "@extensibility(mutable): only final structs"},
      {"struct S { long double v; };", "long double is not supported"},
      {"struct S { wchar c; };", "wchar is not supported"},
      {"struct S { Unknown u; };", "unknown type 'Unknown'"},
      {"struct T;\nstruct S { T t; };", "msg.idl:2: struct T is declared but not defined"},
      {"struct S { double v; double v; };", "member 'v' twice"},
      {"struct S { double v[0]; };", "an array of 0 elements"},
      {"struct S { double v[70000]; };", "more than 65536 elements"},
      {"struct S { octet a[65536]; double b; };", "exceeds 65536 bytes"},
      {"struct S { };", "struct S has no members"},
      {"union U switch (long) { case 1: double a; };", "'union' is not supported"},
      {"struct S : Base { double v; };", "inheritance is not supported"},
      {"struct S { double v; }; struct S { double w; };", "struct S is defined twice"},
      {"struct S { double v; /* open", "comment not closed"},
      {"module m { struct S { double v; };", "expected"},
      {"struct S { double v[N]; };", "'N' is not an integer constant"},
      {"const long N = 4294967296; struct S { double v[2]; };", "constant 4294967296 is too large"},
      {"const long N = 99999999999999999999; struct S { double v[2]; };", "constant 99999999999999999999 is too large"},
      {"const long N = 65536 * 65536; struct S { double v[2]; };", "constant 4294967296 is too large"},
      {"const long N = 4294967295 + 1; struct S { double v[2]; };", "constant 4294967296 is too large"},
      {"const long N = 2 - 3; struct S { double v[2]; };", "negative constant"},
      {"const long N = 2 / 0; struct S { double v[2]; };", "division by zero"},
      {"struct S { double v; } $", "unexpected character '$'"},
      {"", "defines no struct"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.text);
    const std::string why = Refusal(c.text);
    CHECK_MESSAGE(why.find(c.want) != std::string::npos, why);
  }
  CHECK(Refusal("struct S { double v; };", "T").find("no struct 'T' (known: S)") != std::string::npos);
  CHECK(Refusal("#include \"gone.idl\"\nstruct S { double v; };").find("msg.idl:1: #include \"gone.idl\"") !=
        std::string::npos);
  // An include cycle is read once per file, not forever.
  Files files;
  files.text["dir/x.idl"] = "#include \"msg.idl\"\nstruct X { double x; };";
  CHECK(Ok("#include \"x.idl\"\nstruct S { X x; };", "", files).leaves.size() == 1);
}

TEST_CASE("idl: strings and sequences (ROS 2's sensor_msgs/Joy) are laid out with the elements the robot file names") {
  Files files;
  files.text["dir/Time_.idl"] =
      "module builtin_interfaces { module msg { module dds_ {\n"
      "struct Time_ { int32 sec; uint32 nanosec; }; }; }; };";
  files.text["dir/Header_.idl"] =
      "#include \"Time_.idl\"\n"
      "module std_msgs { module msg { module dds_ {\n"
      "struct Header_ { builtin_interfaces::msg::dds_::Time_ stamp; string frame_id; };"
      " }; }; };";
  const std::string joy =
      "#include \"Header_.idl\"\n"
      "module sensor_msgs { module msg { module dds_ {\n"
      "struct Joy_ { std_msgs::msg::dds_::Header_ header; sequence<float> axes;"
      " sequence<int32> buttons; }; }; }; };";
  IdlMessage m = Ok(joy, "", files);
  CHECK(m.type_name == "sensor_msgs::msg::dds_::Joy_");
  REQUIRE(m.variable());
  CHECK(m.c_size == 0);  // no fixed memory layout
  // The wire order: sec, nanosec, frame_id's length, axes' count, buttons' count.
  REQUIRE(m.items.size() == 5);
  CHECK(m.items[2].kind == IdlItem::Kind::kString);
  CHECK(m.items[2].path == "header.frame_id");
  CHECK(m.items[3].kind == IdlItem::Kind::kSequence);
  CHECK(m.items[3].path == "axes");
  CHECK(m.items[3].element == IdlScalar::kFloat);
  CHECK(m.items[4].element == IdlScalar::kInt32);
  // No element until one is named: sec 0, nanosec 4, frame_id's length 8 and its NUL 12, axes' count
  // at 16, buttons' at 20.
  CHECK(m.leaves.size() == 2);
  CHECK(m.items[2].cdr_offset == 8);
  CHECK(m.items[3].cdr_offset == 16);
  CHECK(m.items[4].cdr_offset == 20);
  CHECK(m.cdr_size == 24);
  CHECK(m.LeafIndex("axes[1]") == -1);
  // Naming axes[1] holds axes[0] and axes[1]; buttons[2] holds three buttons, after them.
  const int a1 = m.Element("axes[1]");
  REQUIRE(a1 >= 0);
  CHECK(m.leaves[static_cast<std::size_t>(a1)].path == "axes[1]");
  CHECK(Leaf(m, "axes[0]").cdr_offset == 20);
  CHECK(Leaf(m, "axes[1]").cdr_offset == 24);
  CHECK(m.items[4].cdr_offset == 28);
  CHECK(m.Element("buttons[2]") >= 0);
  CHECK(Leaf(m, "buttons[0]").cdr_offset == 32);
  CHECK(Leaf(m, "buttons[2]").cdr_offset == 40);
  CHECK(m.cdr_size == 44);
  // Naming one held already changes nothing; the leaves named before keep their indices.
  CHECK(m.Element("axes[0]") == m.LeafIndex("axes[0]"));
  CHECK(m.Element("axes[1]") == a1);
  CHECK(m.leaves.size() == 7);
  // Not members: a string's characters, an element past 65535, no index, another name.
  CHECK(m.Element("header.frame_id[0]") == -1);
  CHECK(m.Element("axes[65536]") == -1);
  CHECK(m.Element("axes[]") == -1);
  CHECK(m.Element("axes[x]") == -1);
  CHECK(m.Element("wheels[0]") == -1);
  CHECK(m.leaves.size() == 7);
}

TEST_CASE("idl: bounded strings and sequences, doubles after a string, and a layout that would grow past 65536 bytes") {
  IdlMessage m = Ok("const long N = 3;\nstruct S { string<8> name; double d; sequence<double, N> v; octet tail; };");
  REQUIRE(m.variable());
  CHECK(m.items[0].bound == 8);
  CHECK(m.items[2].bound == 3);
  // name: length at 0 and its NUL at 4; d aligned to 8; v's count at 16.
  CHECK(Leaf(m, "d").cdr_offset == 8);
  CHECK(m.items[2].cdr_offset == 16);
  CHECK(Leaf(m, "tail").cdr_offset == 20);
  CHECK(m.Element("v[3]") == -1);  // past the bound of 3
  REQUIRE(m.Element("v[2]") >= 0);
  CHECK(Leaf(m, "v[0]").cdr_offset == 24);  // doubles aligned to 8 after the count
  CHECK(Leaf(m, "v[2]").cdr_offset == 40);
  CHECK(Leaf(m, "tail").cdr_offset == 48);
  CHECK(m.cdr_size == 49);
  // Arrays of strings: one string per element; a struct with a string nested in an array.
  IdlMessage n = Ok("struct P { string id; float x; };\nstruct S { string names[2]; P p[2]; };");
  CHECK(n.items.size() == 6);
  CHECK(n.items[1].path == "names[1]");
  CHECK(n.items[4].path == "p[1].id");
  // Lengths at 0, 8 (names), 16 (p[0].id), p[0].x at 24, p[1].id's length at 28 and its NUL at 32.
  CHECK(Leaf(n, "p[0].x").cdr_offset == 24);
  CHECK(Leaf(n, "p[1].x").cdr_offset == 36);
  CHECK(n.cdr_size == 40);
}
