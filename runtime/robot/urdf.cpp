#include "runtime/robot/urdf.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "runtime/core/enum_name.hpp"
#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::robot {
namespace {

// ---- A small XML reader: elements, attributes, comments, processing instructions. ----------

struct XmlElement {
  std::string name;
  int line = 0;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::vector<std::unique_ptr<XmlElement>> children;

  const std::string* Attribute(const std::string& key) const {
    for (const auto& [k, v] : attributes)
      if (k == key) return &v;
    return nullptr;
  }
  const XmlElement* Child(const std::string& child) const {
    for (const auto& c : children)
      if (c->name == child) return c.get();
    return nullptr;
  }
};

class XmlReader {
 public:
  XmlReader(const std::string& text, std::string origin) : s_(text), origin_(std::move(origin)) {}

  Result<std::unique_ptr<XmlElement>> Document() {
    std::unique_ptr<XmlElement> root;
    while (true) {
      SkipSpace();
      if (pos_ >= s_.size()) break;
      if (Starts("<?")) {
        if (!SkipPast("?>")) return Fail("unterminated '<?'");
      } else if (Starts("<!--")) {
        if (!SkipPast("-->")) return Fail("unterminated comment");
      } else if (Starts("<!")) {
        if (!SkipPast(">")) return Fail("unterminated '<!'");
      } else if (Starts("<")) {
        if (root) return Fail("a second root element");
        auto e = Element();
        if (!e.ok()) return std::move(e).error();
        root = std::move(*e);
      } else {
        return Fail("text outside the root element");
      }
    }
    if (!root) return Fail("no root element");
    return root;
  }

 private:
  Error Fail(const std::string& what) const {
    return MakeError(ErrorCode::kFormat, origin_ + ":" + std::to_string(Line()) + ": XML: " + what);
  }
  int Line() const {
    int line = 1;
    for (std::size_t i = 0; i < pos_ && i < s_.size(); ++i) line += s_[i] == '\n' ? 1 : 0;
    return line;
  }
  bool Starts(const char* p) const { return s_.compare(pos_, std::char_traits<char>::length(p), p) == 0; }
  bool SkipPast(const char* p) {
    const std::size_t at = s_.find(p, pos_);
    if (at == std::string::npos) return false;
    pos_ = at + std::char_traits<char>::length(p);
    return true;
  }
  void SkipSpace() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_])) != 0) ++pos_;
  }
  static bool NameChar(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-' || c == '.' || c == ':';
  }
  std::string Name() {
    const std::size_t b = pos_;
    while (pos_ < s_.size() && NameChar(s_[pos_])) ++pos_;
    return s_.substr(b, pos_ - b);
  }
  Result<std::string> Unescape(const std::string& raw) const {
    std::string out;
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] != '&') {
        out += raw[i];
        continue;
      }
      const std::size_t semi = raw.find(';', i);
      if (semi == std::string::npos) return Fail("'&' without ';' in an attribute value");
      const std::string ent = raw.substr(i + 1, semi - i - 1);
      if (ent == "lt")
        out += '<';
      else if (ent == "gt")
        out += '>';
      else if (ent == "amp")
        out += '&';
      else if (ent == "quot")
        out += '"';
      else if (ent == "apos")
        out += '\'';
      else
        return Fail("unknown entity '&" + ent + ";'");
      i = semi;
    }
    return out;
  }

  Result<std::unique_ptr<XmlElement>> Element() {
    auto e = std::make_unique<XmlElement>();
    e->line = Line();
    ++pos_;  // '<'
    e->name = Name();
    if (e->name.empty()) return Fail("element without a name");
    while (true) {
      SkipSpace();
      if (pos_ >= s_.size()) return Fail("unterminated element <" + e->name + ">");
      if (Starts("/>")) {
        pos_ += 2;
        return e;
      }
      if (s_[pos_] == '>') {
        ++pos_;
        break;
      }
      const std::string key = Name();
      if (key.empty()) return Fail("bad character '" + std::string(1, s_[pos_]) + "' in <" + e->name + ">");
      SkipSpace();
      if (pos_ >= s_.size() || s_[pos_] != '=')
        return Fail("attribute '" + key + "' of <" + e->name + "> has no value");
      ++pos_;
      SkipSpace();
      if (pos_ >= s_.size() || (s_[pos_] != '"' && s_[pos_] != '\''))
        return Fail("attribute '" + key + "' of <" + e->name + "> is not quoted");
      const char q = s_[pos_++];
      const std::size_t end = s_.find(q, pos_);
      if (end == std::string::npos) return Fail("unterminated value of attribute '" + key + "'");
      auto value = Unescape(s_.substr(pos_, end - pos_));
      if (!value.ok()) return std::move(value).error();
      pos_ = end + 1;
      if (e->Attribute(key) != nullptr) return Fail("attribute '" + key + "' repeated in <" + e->name + ">");
      e->attributes.emplace_back(key, std::move(*value));
    }
    // Content: children, comments, text (ignored), then the end tag.
    while (true) {
      const std::size_t lt = s_.find('<', pos_);
      if (lt == std::string::npos) {
        pos_ = s_.size();
        return MakeError(ErrorCode::kFormat,
                         origin_ + ":" + std::to_string(e->line) + ": XML: element <" + e->name + "> is not closed");
      }
      pos_ = lt;
      if (Starts("<!--")) {
        if (!SkipPast("-->")) return Fail("unterminated comment");
      } else if (Starts("<![CDATA[")) {
        if (!SkipPast("]]>")) return Fail("unterminated CDATA");
      } else if (Starts("</")) {
        pos_ += 2;
        const std::string end = Name();
        SkipSpace();
        if (end != e->name || pos_ >= s_.size() || s_[pos_] != '>')
          return Fail("<" + e->name + "> closed by </" + end + ">");
        ++pos_;
        return e;
      } else if (Starts("<?")) {
        if (!SkipPast("?>")) return Fail("unterminated '<?'");
      } else {
        auto child = Element();
        if (!child.ok()) return std::move(child).error();
        e->children.push_back(std::move(*child));
      }
    }
  }

  const std::string& s_;
  std::string origin_;
  std::size_t pos_ = 0;
};

// ---- URDF ------------------------------------------------------------------------------------

class UrdfParser {
 public:
  explicit UrdfParser(std::string origin) : origin_(std::move(origin)) {}

  Error Fail(const std::string& where, const std::string& what) const {
    return MakeError(ErrorCode::kInvalidValue, origin_ + ": " + where + ": " + what);
  }

  // A required attribute holding `count` whitespace-separated finite numbers.
  Status Numbers(const XmlElement* e, const std::string& where, const char* key, double* out, int count,
                 bool required = true) const {
    const std::string* v = e != nullptr ? e->Attribute(key) : nullptr;
    if (v == nullptr) return required ? Status(Fail(where, std::string("missing attribute '") + key + "'")) : Status();
    std::istringstream ss(*v);
    for (int i = 0; i < count; ++i) {
      std::string tok;
      if (!(ss >> tok))
        return Fail(where + "." + key, "'" + *v + "' has fewer than " + std::to_string(count) + " numbers");
      char* end = nullptr;
      const double d = std::strtod(tok.c_str(), &end);
      if (*end != '\0') return Fail(where + "." + key, "'" + tok + "' is not a number");
      if (!std::isfinite(d)) return Fail(where + "." + key, "'" + tok + "' is not finite");
      out[i] = d;
    }
    std::string extra;
    if (ss >> extra) return Fail(where + "." + key, "'" + *v + "' has more than " + std::to_string(count) + " numbers");
    return {};
  }

  Status Pose(const XmlElement* e, const std::string& where, UrdfPose* pose) const {
    if (e == nullptr) return {};  // URDF: a missing origin is the identity
    if (auto s = Numbers(e, where, "xyz", pose->xyz.data(), 3, false); !s) return s;
    return Numbers(e, where, "rpy", pose->rpy.data(), 3, false);
  }

  Status Positive(double v, const std::string& field) const {
    if (!(v > 0)) {
      std::string what = "'";
      what += Str(v);
      what += "' is not a positive number";
      return Fail(field, what);
    }
    return {};
  }

  static std::string Str(double v) {
    std::ostringstream ss;
    ss << v;
    return ss.str();
  }

  Status Link(const XmlElement& e, UrdfLink* link) const {
    const std::string* name = e.Attribute("name");
    if (name == nullptr || name->empty())
      return Fail("link (line " + std::to_string(e.line) + ")", "missing attribute 'name'");
    link->name = *name;
    const std::string where = "link '" + *name + "'";
    if (const XmlElement* in = e.Child("inertial"); in != nullptr) {
      link->has_inertial = true;
      UrdfInertial& I = link->inertial;
      if (auto s = Pose(in->Child("origin"), where + ".inertial.origin", &I.origin); !s) return s;
      const XmlElement* mass = in->Child("mass");
      if (mass == nullptr) return Fail(where + ".inertial", "missing element <mass>");
      if (auto s = Numbers(mass, where + ".inertial.mass", "value", &I.mass_kg, 1); !s) return s;
      if (auto s = Positive(I.mass_kg, where + ".inertial.mass.value"); !s) return s;
      const XmlElement* in_t = in->Child("inertia");
      if (in_t == nullptr) return Fail(where + ".inertial", "missing element <inertia>");
      const std::string w = where + ".inertial.inertia";
      double* fields[6] = {&I.ixx, &I.ixy, &I.ixz, &I.iyy, &I.iyz, &I.izz};
      const char* keys[6] = {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"};
      for (int k = 0; k < 6; ++k)
        if (auto s = Numbers(in_t, w, keys[k], fields[k], 1); !s) return s;
      for (int k : {0, 3, 5})
        if (auto s = Positive(*fields[k], w + "." + keys[k]); !s) return s;
      // Principal moments of a physical body satisfy the triangle inequality; check the diagonal.
      if (I.ixx + I.iyy < I.izz || I.iyy + I.izz < I.ixx || I.ixx + I.izz < I.iyy)
        return Fail(w, "moments ixx " + Str(I.ixx) + ", iyy " + Str(I.iyy) + ", izz " + Str(I.izz) +
                           " violate the triangle inequality");
    }
    for (const auto& c : e.children) {
      if (c->name != "collision") continue;
      const XmlElement* geom = c->Child("geometry");
      if (geom == nullptr) return Fail(where + ".collision", "missing element <geometry>");
      UrdfCollision col;
      if (auto s = Pose(c->Child("origin"), where + ".collision.origin", &col.origin); !s) return s;
      const std::string w = where + ".collision.geometry";
      if (const XmlElement* sphere = geom->Child("sphere"); sphere != nullptr) {
        col.shape = UrdfShape::kSphere;
        if (auto s = Numbers(sphere, w + ".sphere", "radius", &col.size[0], 1); !s) return s;
        if (auto s = Positive(col.size[0], w + ".sphere.radius"); !s) return s;
        if (link->sphere_radius_m == 0) link->sphere_radius_m = col.size[0];
      } else if (const XmlElement* box = geom->Child("box"); box != nullptr) {
        col.shape = UrdfShape::kBox;
        if (auto s = Numbers(box, w + ".box", "size", col.size.data(), 3); !s) return s;
        for (double v : col.size)
          if (auto s = Positive(v, w + ".box.size"); !s) return s;
      } else if (const XmlElement* cyl = geom->Child("cylinder"); cyl != nullptr) {
        col.shape = UrdfShape::kCylinder;
        if (auto s = Numbers(cyl, w + ".cylinder", "radius", &col.size[0], 1); !s) return s;
        if (auto s = Numbers(cyl, w + ".cylinder", "length", &col.size[1], 1); !s) return s;
        if (auto s = Positive(col.size[0], w + ".cylinder.radius"); !s) return s;
        if (auto s = Positive(col.size[1], w + ".cylinder.length"); !s) return s;
      } else {
        return Fail(w, "has no sphere, box or cylinder (the shapes supported)");
      }
      link->collisions.push_back(col);
    }
    return {};
  }

  Status Joint(const XmlElement& e, const std::map<std::string, std::uint32_t>& links, UrdfJoint* j) const {
    const std::string* name = e.Attribute("name");
    if (name == nullptr || name->empty())
      return Fail("joint (line " + std::to_string(e.line) + ")", "missing attribute 'name'");
    j->name = *name;
    const std::string where = "joint '" + *name + "'";
    const std::string* type = e.Attribute("type");
    if (type == nullptr) return Fail(where, "missing attribute 'type'");
    if (*type == "revolute") {
      j->type = UrdfJointType::kRevolute;
    } else if (*type == "continuous") {
      j->type = UrdfJointType::kContinuous;
    } else if (*type == "fixed") {
      j->type = UrdfJointType::kFixed;
    } else {
      return Fail(where + ".type", "'" + *type + "' is not supported (revolute, continuous, fixed)");
    }
    for (const char* role : {"parent", "child"}) {
      const XmlElement* r = e.Child(role);
      if (r == nullptr) return Fail(where, std::string("missing element <") + role + ">");
      const std::string* link = r->Attribute("link");
      if (link == nullptr) return Fail(where + "." + role, "missing attribute 'link'");
      const auto it = links.find(*link);
      if (it == links.end()) return Fail(where + "." + role + ".link", "'" + *link + "' is not a link of this robot");
      (std::string(role) == "parent" ? j->parent : j->child) = it->second;
    }
    if (j->parent == j->child) return Fail(where + ".child.link", "is the joint's parent link");
    if (auto s = Pose(e.Child("origin"), where + ".origin", &j->origin); !s) return s;
    if (j->type == UrdfJointType::kFixed) return {};

    if (const XmlElement* axis = e.Child("axis"); axis != nullptr) {
      if (auto s = Numbers(axis, where + ".axis", "xyz", j->axis.data(), 3); !s) return s;
    }
    const double n = std::sqrt(j->axis[0] * j->axis[0] + j->axis[1] * j->axis[1] + j->axis[2] * j->axis[2]);
    if (!(n > 1e-9)) return Fail(where + ".axis.xyz", "is the zero vector");
    for (double& a : j->axis) a /= n;

    const XmlElement* limit = e.Child("limit");
    const std::string w = where + ".limit";
    if (j->type == UrdfJointType::kContinuous) {
      // No position limits: lower and upper, when given, are ignored; <limit> itself is optional.
      j->lower_rad = -HUGE_VAL;
      j->upper_rad = HUGE_VAL;
    } else {
      if (limit == nullptr)
        return Fail(where, "missing element <limit> (a revolute joint needs lower, upper, effort, velocity)");
      if (auto s = Numbers(limit, w, "lower", &j->lower_rad, 1); !s) return s;
      if (auto s = Numbers(limit, w, "upper", &j->upper_rad, 1); !s) return s;
    }
    if (limit != nullptr) {
      if (auto s = Numbers(limit, w, "effort", &j->effort_nm, 1); !s) return s;
      if (auto s = Numbers(limit, w, "velocity", &j->velocity_rad_s, 1); !s) return s;
      if (!(j->lower_rad < j->upper_rad))
        return Fail(w + ".lower", "'" + Str(j->lower_rad) + "' is not below upper '" + Str(j->upper_rad) + "'");
      if (auto s = Positive(j->effort_nm, w + ".effort"); !s) return s;
      if (auto s = Positive(j->velocity_rad_s, w + ".velocity"); !s) return s;
    }
    if (const XmlElement* dyn = e.Child("dynamics"); dyn != nullptr) {
      if (auto s = Numbers(dyn, where + ".dynamics", "damping", &j->damping_nm_s_rad, 1, false); !s) return s;
      if (auto s = Numbers(dyn, where + ".dynamics", "friction", &j->friction_nm, 1, false); !s) return s;
      if (j->damping_nm_s_rad < 0)
        return Fail(where + ".dynamics.damping", "'" + Str(j->damping_nm_s_rad) + "' is negative");
      if (j->friction_nm < 0) return Fail(where + ".dynamics.friction", "'" + Str(j->friction_nm) + "' is negative");
    }
    return {};
  }

  Result<UrdfModel> Robot(const XmlElement& root) const {
    if (root.name != "robot") return Fail("root element", "<" + root.name + "> is not <robot>");
    UrdfModel m;
    const std::string* name = root.Attribute("name");
    if (name == nullptr || name->empty()) return Fail("robot", "missing attribute 'name'");
    m.name = *name;
    std::map<std::string, std::uint32_t> links;
    for (const auto& c : root.children) {
      if (c->name != "link") continue;
      UrdfLink link;
      if (auto s = Link(*c, &link); !s) return s.error();
      if (links.count(link.name) != 0) return Fail("link '" + link.name + "'", "name used twice");
      links[link.name] = static_cast<std::uint32_t>(m.links.size());
      m.links.push_back(std::move(link));
    }
    if (m.links.empty()) return Fail("robot '" + m.name + "'", "has no <link>");
    std::vector<UrdfJoint> joints;
    std::set<std::string> joint_names;
    std::vector<int> parent_joint(m.links.size(), -1);
    for (const auto& c : root.children) {
      if (c->name != "joint") continue;
      UrdfJoint j;
      if (auto s = Joint(*c, links, &j); !s) return s.error();
      if (!joint_names.insert(j.name).second) return Fail("joint '" + j.name + "'", "name used twice");
      if (parent_joint[j.child] >= 0)
        return Fail("joint '" + j.name + "'.child.link",
                    "'" + m.links[j.child].name + "' is already the child of joint '" +
                        joints[static_cast<std::size_t>(parent_joint[j.child])].name + "'");
      parent_joint[j.child] = static_cast<int>(joints.size());
      joints.push_back(std::move(j));
    }
    int root_link = -1;
    for (std::size_t l = 0; l < m.links.size(); ++l) {
      if (parent_joint[l] >= 0) continue;
      if (root_link >= 0)
        return Fail("robot '" + m.name + "'", "links '" + m.links[static_cast<std::size_t>(root_link)].name +
                                                  "' and '" + m.links[l].name +
                                                  "' both have no parent joint (one tree expected)");
      root_link = static_cast<int>(l);
    }
    if (root_link < 0) return Fail("robot '" + m.name + "'", "every link has a parent joint (the joints form a loop)");
    m.root = static_cast<std::uint32_t>(root_link);
    // Topological order: breadth-first from the root; joints never reached belong to a loop.
    std::vector<bool> placed(joints.size(), false);
    std::vector<std::uint32_t> frontier{m.root};
    for (std::size_t k = 0; k < frontier.size(); ++k)
      for (std::size_t j = 0; j < joints.size(); ++j)
        if (!placed[j] && joints[j].parent == frontier[k]) {
          placed[j] = true;
          frontier.push_back(joints[j].child);
          m.joints.push_back(joints[j]);
        }
    for (std::size_t j = 0; j < joints.size(); ++j)
      if (!placed[j])
        return Fail("joint '" + joints[j].name + "'", "is part of a loop, not reachable from the root link");
    return m;
  }

 private:
  std::string origin_;
};

std::string Base(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

}  // namespace

const char* ToString(UrdfJointType type) noexcept {
  return EnumName(type, {"revolute", "continuous", "fixed"});
}

int UrdfModel::FindLink(const std::string& n) const noexcept {
  for (std::size_t i = 0; i < links.size(); ++i)
    if (links[i].name == n) return static_cast<int>(i);
  return -1;
}

int UrdfModel::FindJoint(const std::string& n) const noexcept {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == n) return static_cast<int>(i);
  return -1;
}

double UrdfModel::TotalMassKg() const noexcept {
  double m = 0;
  for (const auto& l : links) m += l.has_inertial ? l.inertial.mass_kg : 0.0;
  return m;
}

Result<UrdfModel> ParseUrdf(const std::string& xml_text, const std::string& origin) {
  XmlReader reader(xml_text, origin);
  auto doc = reader.Document();
  if (!doc.ok()) return std::move(doc).error();
  return UrdfParser(origin).Robot(**doc);
}

Result<UrdfModel> LoadUrdf(const std::string& path) {
  auto text = ReadTextFile(path);
  if (!text.ok()) return std::move(text).error();
  return ParseUrdf(*text, Base(path));
}

Result<RobotDescription> ParseRobotDescription(const std::string& yaml_text, const std::string& origin, UrdfModel urdf,
                                               const std::string& urdf_path) {
  auto doc = ParseYaml(yaml_text, origin);
  if (!doc) return std::move(doc).error();
  const YAML::Node root = *doc;
  const YamlFields f(origin);
  if (auto st = f.Keys(root, "", {"urdf", "joints", "velocity_control", "default_pose", "sit_pose", "stand", "gains"});
      !st)
    return st.error();
  constexpr double kInf = HUGE_VAL;
  RobotDescription d;
  d.urdf = std::move(urdf);
  d.urdf_path = urdf_path;
  const std::string urdf_name = Base(urdf_path);
  YAML::Node joints;
  if (auto st = f.List(root, "joints", "", true, &joints); !st) return st.error();
  std::set<std::string> seen;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const std::string name = joints[i].IsScalar() ? joints[i].as<std::string>() : YamlFields::Quote(joints[i]);
    const std::string where = "joints[" + std::to_string(i) + "]";
    const int j = d.urdf.FindJoint(name);
    if (j < 0) return f.Fail(where, "'" + name + "' is not a joint of " + urdf_name);
    if (!d.urdf.joints[static_cast<std::size_t>(j)].moves())
      return f.Fail(where, "'" + name + "' is not a revolute or continuous joint");
    if (!seen.insert(name).second) return f.Fail(where, "'" + name + "' listed twice");
    d.joint_names.push_back(name);
    d.joint.push_back(static_cast<std::uint32_t>(j));
  }
  for (const auto& j : d.urdf.joints)
    if (j.moves() && seen.count(j.name) == 0)
      return f.Fail("joints",
                    std::string(ToString(j.type)) + " joint '" + j.name + "' of " + urdf_name + " is not listed");

  // Velocity-commanded joints: every continuous one, and any other listed here.
  d.control.assign(d.joint.size(), JointControl::kPosition);
  d.velocity_kd_nm_s_rad.assign(d.joint.size(), 0.0);
  if (root["velocity_control"]) {
    YAML::Node vc;
    if (auto st = f.Map(root, "velocity_control", "", &vc); !st) return st.error();
    for (const auto& kv : vc) {
      const std::string key = kv.first.as<std::string>();
      const std::string w = "velocity_control." + key;
      const auto it = std::find(d.joint_names.begin(), d.joint_names.end(), key);
      if (it == d.joint_names.end()) return f.Fail(w, "is not an actuated joint (joints)");
      const auto i = static_cast<std::size_t>(it - d.joint_names.begin());
      if (auto st = f.Keys(kv.second, w, {"kd_nm_s_rad"}); !st) return st.error();
      if (auto st = f.Number(kv.second, "kd_nm_s_rad", w, 1e-9, kInf, &d.velocity_kd_nm_s_rad[i]); !st)
        return st.error();
      if (!(d.joint_at(i).velocity_rad_s > 0))
        return f.Fail(w, "joint '" + key + "' of " + urdf_name +
                             " has no velocity limit (<limit velocity=...>): a velocity-commanded joint's speed "
                             "limit comes from it");
      d.control[i] = JointControl::kVelocity;
    }
  }
  for (std::size_t i = 0; i < d.joint.size(); ++i) {
    const UrdfJoint& j = d.joint_at(i);
    const std::string where = "joints[" + std::to_string(i) + "]";
    if (j.continuous() && !d.velocity_commanded(i))
      return f.Fail(where, "'" + j.name + "' is a continuous joint of " + urdf_name +
                               ": it takes no position target (give it velocity_control." + j.name + ")");
    if (!(j.effort_nm > 0 && j.velocity_rad_s > 0))
      return f.Fail(where, "'" + j.name + "' of " + urdf_name +
                               " has no <limit> (an actuated joint needs effort and velocity limits)");
  }

  // The default pose: every position-commanded joint, none of the others (a robot of wheels only
  // may leave it out). The sit pose (optional) likewise: where a sit-down ends, before damping.
  YAML::Node stand, gains;
  const bool positions = std::count(d.control.begin(), d.control.end(), JointControl::kPosition) > 0;
  const auto read_pose = [&](const char* key, bool required, std::vector<double>* out) -> Status {
    YAML::Node pose;
    if (required || (root[key] && !root[key].IsNull()))
      if (auto st = f.Map(root, key, "", &pose); !st) return st.error();
    for (const auto& kv : pose) {
      const std::string name = kv.first.as<std::string>();
      if (seen.count(name) == 0) return f.Fail(std::string(key) + "." + name, "is not an actuated joint");
    }
    out->assign(d.joint.size(), 0.0);
    for (std::size_t i = 0; i < d.joint.size(); ++i) {
      const UrdfJoint& j = d.joint_at(i);
      const std::string& name = d.joint_names[i];
      const std::string w = std::string(key) + "." + name;
      if (d.velocity_commanded(i)) {
        if (pose[name])
          return f.Fail(w, YamlFields::Quote(pose[name]) + ": joint '" + name + "' is " +
                               (j.continuous() ? "continuous and " : "") +
                               "velocity-commanded: it takes no position target (it holds zero speed where others "
                               "hold their " +
                               (std::string(key) == "default_pose" ? "default pose)" : "sit pose)"));
        continue;
      }
      if (auto st = f.Number(pose, name.c_str(), key, -kInf, kInf, &(*out)[i]); !st) return st.error();
      if ((*out)[i] < j.lower_rad || (*out)[i] > j.upper_rad)
        return f.Fail(w, YamlFields::Quote(pose[name]) + " is outside the joint's limits [" +
                             YamlFields::Num(j.lower_rad) + ", " + YamlFields::Num(j.upper_rad) + "]");
    }
    return {};
  };
  if (auto st = read_pose("default_pose", positions, &d.default_q_rad); !st) return st.error();
  if (root["sit_pose"] && !root["sit_pose"].IsNull()) {
    if (!positions) return f.Fail("sit_pose", "the robot has no position-commanded joint to sit with");
    if (auto st = read_pose("sit_pose", true, &d.sit_q_rad); !st) return st.error();
  }
  if (auto st = f.Map(root, "stand", "", &stand); !st) return st.error();
  if (auto st = f.Keys(stand, "stand", {"base_height_m"}); !st) return st.error();
  if (auto st = f.Number(stand, "base_height_m", "stand", 1e-3, 100.0, &d.stand_base_height_m); !st) return st.error();
  if (auto st = f.Map(root, "gains", "", &gains); !st) return st.error();
  if (auto st = f.Keys(gains, "gains", {"kp_nm_rad", "kd_nm_s_rad", "damping_kd_nm_s_rad"}); !st) return st.error();
  for (const Status& st : {f.Number(gains, "kp_nm_rad", "gains", 0.0, kInf, &d.kp_nm_rad),
                           f.Number(gains, "kd_nm_s_rad", "gains", 0.0, kInf, &d.kd_nm_s_rad),
                           f.Number(gains, "damping_kd_nm_s_rad", "gains", 1e-9, kInf, &d.damping_kd_nm_s_rad)}) {
    if (!st) return st.error();
  }
  return d;
}

Result<RobotDescription> LoadRobotDescription(const std::string& yaml_path) {
  auto text = ReadTextFile(yaml_path);
  if (!text.ok()) return std::move(text).error();
  const std::string origin = Base(yaml_path);
  auto doc = ParseYaml(*text, origin);
  if (!doc) return std::move(doc).error();
  std::string urdf_name;
  if (auto st = YamlFields(origin).Text(*doc, "urdf", "", &urdf_name); !st) return st.error();
  const std::string urdf_path = (std::filesystem::path(yaml_path).parent_path() / urdf_name).string();
  auto urdf = LoadUrdf(urdf_path);
  if (!urdf.ok()) return std::move(urdf).error();
  return ParseRobotDescription(*text, origin, std::move(*urdf), urdf_path);
}

}  // namespace pbppo::robot
