// The transports section of robot.yaml and timing.lockstep (runtime/robot/transport_spec.hpp).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <span>
#include <string_view>

#include "runtime/core/enum_name.hpp"
#include "runtime/robot/robot_model_parts.hpp"

namespace pbppo::robot {

const char* ToString(MessageDirection d) noexcept {
  return EnumName(d, {"in", "out", "status"});
}

namespace detail {
namespace {

// Why `leaf` names no leaf of `type`: not a member, or an element past a sequence's bound.
std::string NotAMember(const IdlMessage& type, const std::string& leaf) {
  std::string why = "'";
  why += leaf;
  why += "' is not a member of ";
  why += type.type_name;
  const std::string sequence = leaf.substr(0, leaf.rfind('['));
  for (const IdlItem& item : type.items)
    if (item.kind == IdlItem::Kind::kSequence && item.path == sequence)
      why += " (sequence '" + sequence + "' holds " +
             (item.bound != 0 ? "at most " + std::to_string(item.bound) + " elements, from [0]"
                              : "elements [0] to [65535]") +
             ", within 65536 bytes)";
  return why;
}

using Rule = YamlFields::TextRule;
using Kind = ValueTerm::Kind;

// "count.stale_sample" names safety::Cause::kStaleSample ("stale sample"): spaces and hyphens as _.
int CauseIndex(const std::string& name) {
  for (std::size_t c = 0; c < safety::kCauseCount; ++c) {
    std::string n = safety::ToString(static_cast<safety::Cause>(c));
    std::replace_if(n.begin(), n.end(), [](char ch) { return ch == ' ' || ch == '-'; }, '_');
    if (n == name) return static_cast<int>(c);
  }
  return -1;
}

int MotorIndex(const RobotModel& m, const std::string& joint) {
  for (std::size_t k = 0; k < m.motors.size(); ++k)
    if (m.motors[k].joint == joint) return static_cast<int>(k);
  return -1;
}

// Every "{key}" in `s` replaced by `value`.
std::string Replace(std::string s, const std::string& key, const std::string& value) {
  for (std::size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + value.size()))
    s.replace(at, key.size(), value);
  return s;
}

std::string Trim(const std::string& s) {
  const std::size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

}  // namespace

Status Builder::Transports(const YAML::Node& root) {
  YAML::Node list;
  PBPPO_TRY(f.List(root, "transports", "", true, &list));
  if (list.size() == 0) return f.Fail("transports", "is empty");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string w = "transports[" + std::to_string(i) + "]";
    const YAML::Node& n = list[i];
    if (!n.IsMap()) return f.Fail(w, "expected a mapping");
    TransportSpec t;
    PBPPO_TRY(f.Text(n, "name", w, &t.name, Rule::kToken));
    PBPPO_TRY(f.Text(n, "kind", w, &t.kind, Rule::kToken));
    if (m.TransportIndex(t.name) >= 0) return f.Fail(w + ".name", "transport '" + t.name + "' appears twice");
    std::string when = "always";
    PBPPO_TRY(f.OptionalText(n, "when", w, &when, Rule::kToken));
    if (when != "always" && when != "policy") return f.Fail(w + ".when", "'" + when + "' is not always or policy");
    t.policy_only = when == "policy";
    if (t.kind == "can") {
      PBPPO_TRY(f.Keys(n, w, {"name", "kind", "when"}));
    } else if (t.kind == "dds") {
      PBPPO_TRY(
          f.Keys(n, w, {"name", "kind", "when", "participant_profile", "topic_prefix", "wait_for_peer", "messages"}));
      DdsTransportSpec& d = t.dds;
      d.topic_prefix = "pbppo/" + m.name + "/";
      PBPPO_TRY(f.OptionalText(n, "participant_profile", w, &d.participant_profile, Rule::kToken));
      PBPPO_TRY(f.OptionalText(n, "topic_prefix", w, &d.topic_prefix, Rule::kToken));
      PBPPO_TRY(f.Bool(n, "wait_for_peer", w, &d.wait_for_peer));
    } else if (t.kind == "evdev") {
      PBPPO_TRY(f.Keys(n, w, {"name", "kind", "when", "device", "reopen_s", "stream", "axes", "buttons"}));
      PBPPO_TRY(f.Text(n, "device", w, &t.evdev.device));
      PBPPO_TRY(f.OptionalNumber(n, "reopen_s", w, 0.01, 3600, &t.evdev.reopen_s));
    } else {
      return f.Fail(w + ".kind", "'" + t.kind + "' is not can, dds or evdev");
    }
    m.transports.push_back(std::move(t));
  }
  return {};
}

Result<std::vector<ValueTerm>> Builder::Value(const std::string& text, bool status, const std::string& where) const {
  std::vector<ValueTerm> terms;
  std::size_t from = 0;
  for (;;) {
    const std::size_t plus = text.find(" + ", from);
    const std::string term = Trim(text.substr(from, plus == std::string::npos ? plus : plus - from));
    const std::string head = term.substr(0, term.find('.'));
    const std::string name = term.find('.') == std::string::npos ? "" : term.substr(term.find('.') + 1);
    ValueTerm v;
    char* end = nullptr;
    v.value = std::strtod(term.c_str(), &end);
    int index = 0;
    const std::pair<const char*, Kind> plain[] = {{"tick", Kind::kTick},
                                                  {"mode", Kind::kMode},
                                                  {"clock_ns", Kind::kClockNs},
                                                  {"sequence", Kind::kSequence},
                                                  {"phase", Kind::kPhase},
                                                  {"cause", Kind::kCause},
                                                  {"deadline_misses", Kind::kDeadlineMisses},
                                                  {"tick_median_us", Kind::kTickMedianUs},
                                                  {"tick_max_us", Kind::kTickMaxUs}};
    const auto known = std::find_if(std::begin(plain), std::end(plain), [&](const auto& p) { return term == p.first; });
    if (!term.empty() && end != nullptr && *end == '\0' && std::isfinite(v.value)) {
      v.kind = Kind::kConstant;
    } else if (known != std::end(plain)) {
      v.kind = known->second;
    } else if (head == "command" && (index = m.CommandIndex(name)) >= 0) {
      v.kind = Kind::kCommand;
    } else if (head == "field" && (index = m.FieldIndex(name)) >= 0) {
      v.kind = Kind::kField;
    } else if (head == "samples" && (index = m.StreamIndex(name)) >= 0) {
      v.kind = Kind::kSamples;
    } else if (head == "count" && (index = CauseIndex(name)) >= 0) {
      v.kind = Kind::kCount;
    } else if (head == "motor" && !status && (index = MotorIndex(m, name)) >= 0) {
      v.kind = Kind::kMotorOn;
    } else {
      return f.Fail(where, "'" + term +
                               "' is not a value (a number, tick, mode, clock_ns, sequence, command.<name>, "
                               "field.<name>, samples.<stream>; in out messages also motor.<joint>; in status "
                               "messages also phase, cause, count.<cause>, deadline_misses, tick_median_us, "
                               "tick_max_us)");
    }
    const bool status_only = v.kind == Kind::kPhase || v.kind == Kind::kCause || v.kind == Kind::kCount ||
                             v.kind == Kind::kDeadlineMisses || v.kind == Kind::kTickMedianUs ||
                             v.kind == Kind::kTickMaxUs;
    if (status_only && !status)
      return f.Fail(where, "'" + term + "' is the controller's status: only status messages carry it");
    v.index = static_cast<std::uint32_t>(index);
    terms.push_back(v);
    if (plus == std::string::npos) break;
    from = plus + 3;
  }
  return terms;
}

std::vector<std::pair<std::string, std::string>> Builder::PerMotor(const YAML::Node& map) const {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>(), value = kv.second.IsScalar() ? kv.second.as<std::string>() : "";
    const auto per_motor = [](const std::string& t) {
      return t.find("{joint}") != std::string::npos || t.find("{motor}") != std::string::npos;
    };
    if (!per_motor(key) && !per_motor(value)) {
      out.emplace_back(key, value);
      continue;
    }
    for (std::size_t k = 0; k < m.motors.size(); ++k) {
      const auto expand = [&](const std::string& t) {
        return Replace(Replace(t, "{joint}", m.motors[k].joint), "{motor}", std::to_string(k));
      };
      out.emplace_back(expand(key), expand(value));
    }
  }
  return out;
}

Status Builder::InMessage(const YAML::Node& n, const std::string& w, std::uint32_t transport, DdsMessageSpec* out) {
  // stream: a name, or a list of names ("motors": every motor's stream, in the robot's order).
  std::vector<std::string> names;
  if (!n["stream"]) return f.Fail(w, "missing field 'stream'");
  if (n["stream"].IsSequence()) {
    for (const YAML::Node& e : n["stream"]) {
      if (!e.IsScalar()) return f.Fail(w + ".stream", "expected stream names, got " + YamlFields::Quote(e));
      names.push_back(e.as<std::string>());
    }
  } else {
    std::string one;
    PBPPO_TRY(f.Text(n, "stream", w, &one, Rule::kToken));
    names.push_back(one);
  }
  if (names.empty()) return f.Fail(w + ".stream", "names no stream");
  for (const std::string& name : names) {
    std::vector<std::uint32_t> add;
    if (name == "motors" && m.StreamIndex(name) < 0) {
      if (m.motors.empty()) return f.Fail(w + ".stream", "'motors': the robot has no motors");
      for (const MotorSpec& mo : m.motors) add.push_back(mo.stream);
    } else {
      const int s = m.StreamIndex(name);
      if (s < 0) return f.Fail(w + ".stream", "'" + name + "' is not a stream of the robot");
      add.push_back(static_cast<std::uint32_t>(s));
    }
    for (const std::uint32_t s : add) {
      const StreamSpec& spec = m.streams[s];
      if (spec.transport != m.transports[transport].name)
        return f.Fail(w + ".stream", "stream '" + spec.name + "' is delivered by transport '" + spec.transport + "'");
      if (std::find(out->streams.begin(), out->streams.end(), s) != out->streams.end())
        return f.Fail(w + ".stream", "stream '" + spec.name + "' is named twice");
      out->streams.push_back(s);
    }
  }
  out->stream = out->streams.front();
  const std::string stream = names.size() == 1 ? names.front() : "the message's streams";
  PBPPO_TRY(f.OptionalNumber(n, "lost_after_s", w, 0.0, 3600.0, &out->lost_after_s));
  std::string durability = "transient_local";
  PBPPO_TRY(f.OptionalText(n, "durability", w, &durability, Rule::kToken));
  if (durability != "transient_local" && durability != "volatile")
    return f.Fail(w + ".durability", "'" + durability + "' is not transient_local or volatile");
  out->transient_local = durability == "transient_local";
  IdlMessage& type = out->type;  // a sequence's elements are added as the mapping names them
  // The message's fields, stream by stream; the leaf that fills each.
  std::vector<std::uint32_t> field_list;
  for (const std::uint32_t s : out->streams)
    for (std::uint32_t k = 0; k < m.streams[s].field_count; ++k) field_list.push_back(m.streams[s].first_field + k);
  std::vector<int> leaf_of(field_list.size(), -1);
  std::vector<FieldLeaf> read_of(field_list.size());  // how each slot's leaf is read (FieldLeaf)
  const auto slot_of = [&](int fi) -> int {
    const auto at = std::find(field_list.begin(), field_list.end(), static_cast<std::uint32_t>(fi));
    return at == field_list.end() ? -1 : static_cast<int>(at - field_list.begin());
  };
  // The checksum's field is filled by the checksum, not by a leaf.
  PBPPO_TRY(Checksum(n, w, out));
  if (out->checksum.present && out->checksum.field >= 0) {
    const int slot = slot_of(out->checksum.field);
    if (slot < 0)
      return f.Fail(w + ".checksum.field", "'" + m.fields[static_cast<std::size_t>(out->checksum.field)].name +
                                               "' is not a field of " + stream);
    leaf_of[static_cast<std::size_t>(slot)] = static_cast<int>(out->checksum.leaf);
  }
  auto bind = [&](const std::string& field, const std::string& member, const std::string& fw) -> Status {
    // LEAF, or a function of it: increase(LEAF), bit(LEAF, N), float32(LEAF) (FieldLeaf).
    FieldLeaf how;
    std::string leaf = member, bit;
    for (const auto& [name, read] : {std::pair{std::string_view("increase("), FieldLeaf::Read::kIncrease},
                                     std::pair{std::string_view("bit("), FieldLeaf::Read::kBit},
                                     std::pair{std::string_view("float32("), FieldLeaf::Read::kFloat32}}) {
      if (!member.starts_with(name) || !member.ends_with(")")) continue;
      how.read = read;
      leaf = member.substr(name.size(), member.size() - name.size() - 1);
      if (read == FieldLeaf::Read::kBit) {
        const auto comma = leaf.rfind(',');
        if (comma == std::string::npos) return f.Fail(fw, "'" + member + "': expected bit(LEAF, N)");
        bit = leaf.substr(comma + 1);
        leaf = leaf.substr(0, comma);
        while (!bit.empty() && bit.front() == ' ') bit.erase(bit.begin());
      }
    }
    const int fi = m.FieldIndex(field), li = type.Element(leaf);
    const int slot = fi < 0 ? -1 : slot_of(fi);
    if (slot < 0)
      return f.Fail(fw,
                    "'" + field + "' is not a field of " + (names.size() == 1 ? "stream '" + stream + "'" : stream));
    if (li < 0) return f.Fail(fw, NotAMember(type, leaf));
    if (leaf_of[static_cast<std::size_t>(slot)] >= 0) return f.Fail(fw, "field '" + field + "' is filled twice");
    const IdlScalar t = type.leaves[static_cast<std::size_t>(li)].type;
    const std::uint32_t mask = IdlCounterMask(t);
    if (how.read == FieldLeaf::Read::kIncrease && mask == 0)
      return f.Fail(fw,
                    "'" + member + "': " + leaf + " is a " + ToString(t) + ", not a counter (uint8, uint16 or uint32)");
    if (how.read == FieldLeaf::Read::kBit) {
      if (mask == 0)
        return f.Fail(fw, "'" + member + "': " + leaf + " is a " + ToString(t) +
                              ", not an unsigned integer (uint8, uint16 or uint32) to take a bit of");
      const int width = mask == 0xffu ? 8 : mask == 0xffffu ? 16 : 32;
      const bool digits = !bit.empty() && bit.size() <= 2 &&
                          std::all_of(bit.begin(), bit.end(), [](char c) { return c >= '0' && c <= '9'; });
      if (!digits || std::stoi(bit) >= width)
        return f.Fail(fw, "'" + member + "': bit '" + bit + "' is not one of the " + std::to_string(width) +
                              " bits of " + leaf + " (0 to " + std::to_string(width - 1) + ")");
      how.bit = static_cast<std::uint8_t>(std::stoi(bit));
    }
    if (how.read == FieldLeaf::Read::kFloat32) {
      const auto& leaves = type.leaves;
      const auto at = static_cast<std::size_t>(li);
      // Four octets of one array: the leaves' names the same up to the index.
      const auto array_of = [](const std::string& name) { return name.substr(0, name.rfind('[')); };
      bool octets = at + 4 <= leaves.size();
      for (std::size_t k = 0; octets && k < 4; ++k)
        octets = leaves[at + k].type == IdlScalar::kUint8 && leaves[at + k].cdr_offset == leaves[at].cdr_offset + k &&
                 leaves[at].path.find('[') != std::string::npos &&
                 array_of(leaves[at + k].path) == array_of(leaves[at].path);
      if (!octets)
        return f.Fail(fw, "'" + member + "': " + leaf + " does not begin four octets of one array (a " + ToString(t) +
                              " leaf; float32() reads a float inside a byte array)");
    }
    leaf_of[static_cast<std::size_t>(slot)] = li;
    read_of[static_cast<std::size_t>(slot)] = how;
    return {};
  };
  if (const YAML::Node map = n["fields"]) {
    if (!map.IsMap()) return f.Fail(w + ".fields", "expected a mapping of fields to members");
    for (const auto& [field, leaf] : PerMotor(map)) {
      const std::string fw = w + ".fields." + field;
      if (field.find("{i}") == std::string::npos) {
        PBPPO_TRY(bind(field, leaf, fw));
        continue;
      }
      std::uint32_t i = 0;
      for (; m.FieldIndex(ExpandIndex(field, i)) >= 0; ++i)
        PBPPO_TRY(bind(ExpandIndex(field, i), ExpandIndex(leaf, i), fw));
      if (i == 0) return f.Fail(fw, "no field matches '" + field + "'");
    }
  }
  // Fields shaped as a stick: {field: {range, scale, dead_zone}}.
  if (const YAML::Node axes = n["axes"]) {
    if (!axes.IsMap()) return f.Fail(w + ".axes", "expected a mapping field: {scale, dead_zone, range}");
    for (const auto& kv : axes) {
      const std::string field = kv.first.IsScalar() ? kv.first.as<std::string>() : YamlFields::Quote(kv.first);
      const std::string wa = w + ".axes." + field;
      const int fi = m.FieldIndex(field);
      const int slot = fi < 0 ? -1 : slot_of(fi);
      if (slot < 0)
        return f.Fail(wa,
                      "'" + field + "' is not a field of " + (names.size() == 1 ? "stream '" + stream + "'" : stream));
      if (!kv.second.IsMap()) return f.Fail(wa, "expected a mapping {scale, dead_zone, range}");
      PBPPO_TRY(f.Keys(kv.second, wa, {"scale", "dead_zone", "range"}));
      FieldLeaf& how = read_of[static_cast<std::size_t>(slot)];
      if (how.read == FieldLeaf::Read::kIncrease || how.read == FieldLeaf::Read::kBit ||
          static_cast<std::int32_t>(fi) == out->checksum.field)
        return f.Fail(wa, "field '" + field + "' is a count, a bit or a checksum's verdict, not a stick");
      PBPPO_TRY(ReadAxisShape(m, f, kv.second, wa, static_cast<std::uint32_t>(fi), false, &how.axis));
      how.shaped = true;
    }
  }
  for (std::size_t k = 0; k < field_list.size(); ++k) {
    const FieldSpec& field = m.fields[field_list[k]];
    if (leaf_of[k] < 0) leaf_of[k] = type.LeafIndex(field.name);
    if (leaf_of[k] < 0)
      return f.Fail(w, "field '" + field.name + "' of stream '" + m.streams[field.stream].name +
                           "' is filled by no member of " + type.type_name + " (name it under fields)");
    // The checksum's field is set by the transport, not decoded from a leaf.
    if (static_cast<std::int32_t>(field_list[k]) == out->checksum.field) continue;
    FieldLeaf fl = read_of[k];
    fl.field = field_list[k];
    fl.leaf = static_cast<std::uint32_t>(leaf_of[k]);
    out->fields.push_back(fl);
  }
  if (const YAML::Node map = n["peer"]) {
    if (!map.IsMap()) return f.Fail(w + ".peer", "expected a mapping of members to clock_ns or sequence");
    for (const auto& kv : map) {
      const std::string leaf = kv.first.as<std::string>();
      if (!kv.second.IsScalar())
        return f.Fail(w + ".peer." + leaf, "expected clock_ns or sequence, got " + YamlFields::Quote(kv.second));
      const std::string what = kv.second.as<std::string>();
      const int li = type.Element(leaf);
      if (li < 0) return f.Fail(w + ".peer." + leaf, NotAMember(type, leaf));
      if (what != "clock_ns" && what != "sequence")
        return f.Fail(w + ".peer." + leaf, "'" + what + "' is not clock_ns or sequence");
      out->peer.push_back(
          {static_cast<std::uint32_t>(li), what == "sequence" ? PeerLeaf::Kind::kSequence : PeerLeaf::Kind::kClockNs});
    }
  }
  return {};
}

Status Builder::OutMessage(const YAML::Node& n, const std::string& w, DdsMessageSpec* out) {
  YAML::Node map;
  PBPPO_TRY(f.Map(n, "values", w, &map));
  for (const auto& kv : map)
    if (!kv.second.IsScalar())
      return f.Fail(w + ".values." + kv.first.as<std::string>(),
                    "expected a value, got " + YamlFields::Quote(kv.second));
  PBPPO_TRY(Checksum(n, w, out));
  for (const auto& [leaf, value] : PerMotor(map)) {
    const std::string vw = w + ".values." + leaf;
    const int li = out->type.Element(leaf);
    if (li < 0) return f.Fail(vw, NotAMember(out->type, leaf));
    if (out->checksum.present && static_cast<std::uint32_t>(li) == out->checksum.leaf)
      return f.Fail(vw, "'" + leaf + "' carries the checksum");
    auto terms = Value(value, out->direction == MessageDirection::kStatus, vw);
    if (!terms) return std::move(terms).error();
    for (const LeafValue& v : out->values)
      if (v.leaf == static_cast<std::uint32_t>(li)) return f.Fail(vw, "'" + leaf + "' is given twice");
    out->values.push_back({static_cast<std::uint32_t>(li), std::move(*terms)});
  }
  return {};
}

Status Builder::Checksum(const YAML::Node& n, const std::string& w, DdsMessageSpec* out) {
  if (!n["checksum"]) return {};
  const std::string cw = w + ".checksum";
  YAML::Node c;
  PBPPO_TRY(f.Map(n, "checksum", w, &c));
  const bool in = out->direction == MessageDirection::kIn;
  if (in)
    PBPPO_TRY(f.Keys(c, cw, {"leaf", "field", "algorithm"}));
  else
    PBPPO_TRY(f.Keys(c, cw, {"leaf", "algorithm"}));
  std::string leaf, algorithm = "crc32_mpeg2_words", field;
  PBPPO_TRY(f.Text(c, "leaf", cw, &leaf, Rule::kToken));
  PBPPO_TRY(f.OptionalText(c, "algorithm", cw, &algorithm, Rule::kToken));
  if (algorithm != "crc32_mpeg2_words")
    return f.Fail(cw + ".algorithm", "'" + algorithm + "' is not crc32_mpeg2_words");
  const IdlMessage& type = out->type;
  if (type.variable())
    return f.Fail(cw, type.type_name + " has strings or sequences: no fixed memory layout for a checksum to cover");
  const int li = type.LeafIndex(leaf);
  if (li < 0) return f.Fail(cw + ".leaf", "'" + leaf + "' is not a member of " + type.type_name);
  const IdlLeaf& l = type.leaves[static_cast<std::size_t>(li)];
  if (l.type != IdlScalar::kUint32 || l.c_offset + 4 != type.c_size || type.c_size % 4 != 0)
    return f.Fail(cw + ".leaf", "'" + leaf + "' is not a uint32 in the last word of " + type.type_name + " (a " +
                                    ToString(l.type) + " at byte " + std::to_string(l.c_offset) + " of " +
                                    std::to_string(type.c_size) + ")");
  out->checksum.present = true;
  out->checksum.leaf = static_cast<std::uint32_t>(li);
  if (in) {
    PBPPO_TRY(f.Text(c, "field", cw, &field, Rule::kToken));
    out->checksum.field = m.FieldIndex(field);
    if (out->checksum.field < 0) return f.Fail(cw + ".field", "'" + field + "' is not a field of the robot");
    const FieldSpec& fs = m.fields[static_cast<std::size_t>(out->checksum.field)];
    if (!(fs.min > 0 && fs.max < 2))
      return f.Fail(cw + ".field", "'" + field + "' must accept 1 and refuse 0 (min 1, max 1), not [" +
                                       YamlFields::Num(fs.min) + ", " + YamlFields::Num(fs.max) + "]");
  }
  return {};
}

Status Builder::DdsMessage(const YAML::Node& n, const std::string& w, std::uint32_t t, const IdlFileReader& read,
                           const std::string& dir) {
  PBPPO_TRY(f.Keys(n, w,
                   {"topic", "idl", "type", "direction", "stream", "fields", "axes", "peer", "lost_after_s",
                    "durability", "values", "checksum"}));
  DdsMessageSpec msg;
  std::string idl, type, direction;
  PBPPO_TRY(f.Text(n, "topic", w, &msg.topic, Rule::kToken));
  PBPPO_TRY(f.Text(n, "idl", w, &idl, Rule::kToken));
  PBPPO_TRY(f.OptionalText(n, "type", w, &type, Rule::kToken));
  PBPPO_TRY(f.Text(n, "direction", w, &direction, Rule::kToken));
  DdsTransportSpec& spec = m.transports[t].dds;
  for (const DdsMessageSpec& other : spec.messages)
    if (other.topic == msg.topic) return f.Fail(w + ".topic", "topic '" + msg.topic + "' appears twice");
  const bool in = direction == "in";
  if (!in && direction != "out" && direction != "status")
    return f.Fail(w + ".direction", "'" + direction + "' is not in, out or status");
  msg.direction = in ? MessageDirection::kIn : direction == "out" ? MessageDirection::kOut : MessageDirection::kStatus;
  static constexpr const char* kInOnly[] = {"stream", "fields", "axes", "peer", "lost_after_s", "durability"};
  static constexpr const char* kOutOnly[] = {"values"};
  for (const char* key : in ? std::span<const char* const>(kOutOnly) : std::span<const char* const>(kInOnly))
    if (n[key])
      return f.Fail(w + "." + key, std::string("only ") + (in ? "out and status" : "in") + " messages have it");
  const std::string path = (std::filesystem::path(dir) / idl).string();
  auto text = read(path);
  if (!text) return f.Fail(w + ".idl", text.error().message);
  auto parsed = ParseIdlMessage(*text, path, type, read);
  if (!parsed) return f.Fail(w + ".idl", parsed.error().message);
  msg.type = std::move(*parsed);
  msg.type_stem = std::filesystem::path(idl).stem().string();
  PBPPO_TRY(in ? InMessage(n, w, t, &msg) : OutMessage(n, w, &msg));
  spec.messages.push_back(std::move(msg));
  return {};
}

Status Builder::DdsMessages(const YAML::Node& root, const IdlFileReader& read, const std::string& dir) {
  const YAML::Node list = root["transports"];
  for (std::uint32_t t = 0; t < m.transports.size(); ++t) {
    if (m.transports[t].kind != "dds") continue;
    const Status st =
        f.EachItem(list[t], "messages", "transports[" + std::to_string(t) + "]", true,
                   [&](const YAML::Node& n, const std::string& w) { return DdsMessage(n, w, t, read, dir); });
    if (!st) return st;
  }
  // Every stream of a DDS transport arrives in exactly one of its messages.
  for (std::uint32_t s = 0; s < m.streams.size(); ++s) {
    const int t = m.TransportIndex(m.streams[s].transport);
    if (t < 0 || m.transports[static_cast<std::size_t>(t)].kind != "dds") continue;
    int carriers = 0;
    for (const DdsMessageSpec& msg : m.transports[static_cast<std::size_t>(t)].dds.messages)
      carriers += msg.direction == MessageDirection::kIn && std::count(msg.streams.begin(), msg.streams.end(), s) > 0;
    if (carriers != 1)
      return f.Fail("streams", "stream '" + m.streams[s].name + "' arrives in " + std::to_string(carriers) +
                                   " messages of transport '" + m.streams[s].transport + "' (one expected)");
  }
  return {};
}

Status Builder::Lockstep(const YAML::Node& root) {
  const YAML::Node n = root["timing"]["lockstep"];
  if (!n) return {};
  const std::string w = "timing.lockstep";
  if (!n.IsMap()) return f.Fail(w, "expected a mapping {stream, end_field}");
  PBPPO_TRY(f.Keys(n, w, {"stream", "end_field"}));
  std::string stream, end;
  PBPPO_TRY(f.Text(n, "stream", w, &stream, Rule::kToken));
  m.lockstep_stream = m.StreamIndex(stream);
  if (m.lockstep_stream < 0) return f.Fail(w + ".stream", "'" + stream + "' is not a stream of the robot");
  PBPPO_TRY(f.OptionalText(n, "end_field", w, &end, Rule::kToken));
  if (end.empty()) return {};
  m.lockstep_end_field = m.FieldIndex(end);
  if (m.lockstep_end_field < 0 ||
      m.fields[static_cast<std::size_t>(m.lockstep_end_field)].stream != static_cast<std::uint32_t>(m.lockstep_stream))
    return f.Fail(w + ".end_field", "'" + end + "' is not a field of stream '" + stream + "'");
  return {};
}

}  // namespace detail
}  // namespace pbppo::robot
