#include "runtime/robot/idl.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

#include "runtime/robot/yaml_fields.hpp"  // PBPPO_TRY

namespace pbppo::robot {
namespace {

constexpr std::uint32_t kMaxCdrBytes = 65536;
constexpr std::size_t kMaxLeaves = 16384;
constexpr std::uint64_t kMaxArray = 65536;
constexpr int kMaxDepth = 16;

struct Token {
  enum Kind : std::uint8_t { kIdent, kNumber, kString, kPunct, kEnd } kind = kEnd;
  std::string text;
  const std::string* file = nullptr;
  int line = 0;
};

Error IdlError(const std::string& file, int line, const std::string& what) {
  return MakeError(ErrorCode::kInvalidValue, file + ":" + std::to_string(line) + ": " + what);
}

bool IsNameChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
}

// Lays out a message with strings or sequences: each member after the one before, aligned to its
// size (a length to 4), each string empty, each sequence with its `elements`. False when the
// layout exceeds kMaxCdrBytes (the offsets are then not to be used).
bool LayOut(IdlMessage* m) {
  std::uint64_t at = 0;
  auto place = [&](std::uint32_t size) {
    at = (at + size - 1) / size * size;
    const std::uint64_t here = at;
    at += size;
    return static_cast<std::uint32_t>(std::min<std::uint64_t>(here, kMaxCdrBytes));
  };
  for (IdlItem& item : m->items) {
    if (item.kind == IdlItem::Kind::kLeaf) {
      IdlLeaf& l = m->leaves[item.leaf];
      l.cdr_offset = place(IdlScalarSize(l.type));
      continue;
    }
    item.cdr_offset = place(4);
    if (item.kind == IdlItem::Kind::kString) at += 1;  // the NUL of an empty string
    for (const std::uint32_t e : item.elements) m->leaves[e].cdr_offset = place(IdlScalarSize(item.element));
  }
  m->cdr_size = static_cast<std::uint32_t>(std::min<std::uint64_t>(at, kMaxCdrBytes + 1));
  return at <= kMaxCdrBytes;
}

// Tokens of a file and, in place of each #include, of the included file (each file once).
class Lexer {
 public:
  explicit Lexer(const IdlFileReader& read) : read_(read) {}
  Status Add(const std::string& text, const std::string& path, int depth);
  // The name of the first file added (the one whose structs are the default).
  const std::string* main_file() const { return names_.empty() ? nullptr : names_.front().get(); }
  std::vector<Token> tokens;

 private:
  Status Directive(const std::string& line, const std::string& path, int line_no, int depth);
  // The token at text[i] (not a space, comment or directive); `end` receives where it stops.
  Result<Token> Next(const std::string& text, std::size_t i, std::size_t* end, const std::string* file, int line) const;
  const IdlFileReader& read_;
  std::set<std::string> seen_;
  std::vector<std::unique_ptr<std::string>> names_;  // the file names tokens point to
};

Status Lexer::Directive(const std::string& line, const std::string& path, int line_no, int depth) {
  const std::size_t k = line.find_first_not_of(" \t", line.find('#') + 1);
  const std::string word = k == std::string::npos ? "" : line.substr(k, line.find_first_of(" \t\"<", k) - k);
  if (word != "include") return {};  // include guards, #pragma, #define: nothing to read
  const std::size_t open = line.find_first_of("\"<", k);
  const char close = open != std::string::npos && line[open] == '<' ? '>' : '"';
  const std::size_t end = open == std::string::npos ? open : line.find(close, open + 1);
  const std::string file = std::filesystem::path(path).filename().string();
  if (end == std::string::npos) return IdlError(file, line_no, "#include without a file name in quotes or <>");
  const std::string name = line.substr(open + 1, end - open - 1);
  const std::string included = (std::filesystem::path(path).parent_path() / name).lexically_normal().string();
  if (seen_.count(included) != 0) return {};
  if (depth + 1 >= kMaxDepth) return IdlError(file, line_no, "#include \"" + name + "\" nests deeper than 16 files");
  auto text = read_(included);
  if (!text) return IdlError(file, line_no, "#include \"" + name + "\": " + text.error().message);
  return Add(*text, included, depth + 1);
}

Result<Token> Lexer::Next(const std::string& text, std::size_t i, std::size_t* end, const std::string* file,
                          int line) const {
  const char c = text[i];
  Token t;
  t.file = file;
  t.line = line;
  std::size_t j = i + 1;
  auto scope = [&](std::size_t at) { return text.compare(at, 2, "::") == 0; };
  if (IsNameChar(c) && std::isdigit(static_cast<unsigned char>(c)) == 0) {
    t.kind = Token::kIdent;  // names, scoped ones whole ("pbppo_idl::auv::Command")
  } else if (scope(i)) {
    t.kind = Token::kIdent;  // "::a::B"
    j = i + 2;
  } else if (std::isdigit(static_cast<unsigned char>(c)) != 0) {
    t.kind = Token::kNumber;
    while (j < text.size() && (IsNameChar(text[j]) || text[j] == '.')) ++j;
  } else if (c == '"') {
    t.kind = Token::kString;
    j = text.find('"', i + 1);
    if (j == std::string::npos || text.find('\n', i) < j) return IdlError(*file, line, "string not closed");
    ++j;
  } else if (std::string_view("{};:[],<>=@()+-*/|&").find(c) != std::string_view::npos) {
    t.kind = Token::kPunct;
  } else {
    return IdlError(*file, line, std::string("unexpected character '") + c + "'");
  }
  if (t.kind == Token::kIdent)
    while (j < text.size() && (IsNameChar(text[j]) || scope(j))) j += scope(j) ? 2u : 1u;
  t.text = text.substr(i, j - i);
  *end = j;
  return t;
}

Status Lexer::Add(const std::string& text, const std::string& path, int depth) {
  seen_.insert(path);
  names_.push_back(std::make_unique<std::string>(std::filesystem::path(path).filename().string()));
  const std::string* file = names_.back().get();
  int line = 1;
  bool line_start = true;
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '\n' || std::isspace(static_cast<unsigned char>(c)) != 0) {
      line += c == '\n' ? 1 : 0;
      line_start = line_start || c == '\n';
      ++i;
    } else if (c == '#' && line_start) {
      const std::size_t eol = std::min(text.find('\n', i), text.size());
      if (auto st = Directive(text.substr(i, eol - i), path, line, depth); !st) return st;
      i = eol;
    } else if (text.compare(i, 2, "//") == 0) {
      i = std::min(text.find('\n', i), text.size());
    } else if (text.compare(i, 2, "/*") == 0) {
      const std::size_t end = text.find("*/", i + 2);
      if (end == std::string::npos) return IdlError(*file, line, "comment not closed");
      line += static_cast<int>(
          std::count(text.begin() + static_cast<long>(i), text.begin() + static_cast<long>(end), '\n'));
      i = end + 2;
    } else {
      line_start = false;
      std::size_t end = i;
      auto t = Next(text, i, &end, file, line);
      if (!t) return std::move(t).error();
      tokens.push_back(std::move(*t));
      i = end;
    }
  }
  return {};
}

// A type as a member or typedef names it, resolved: a primitive (enums are 32-bit unsigned) or a
// struct, with the array dimensions a typedef adds.
struct TypeRef {
  bool is_struct = false;
  bool is_string = false;    // string, string<N>
  bool is_sequence = false;  // sequence<scalar>, sequence<scalar, N>; the element in `scalar`
  std::uint32_t bound = 0;   // a string's or sequence's; 0 unbounded
  IdlScalar scalar = IdlScalar::kInt32;
  std::string name;  // the struct's qualified name
  std::vector<std::uint32_t> dims;
};

struct Member {
  std::string name;
  TypeRef type;  // dims: the typedef's, then the declarator's
  const std::string* file = nullptr;
  int line = 0;
};

struct StructDef {
  std::vector<Member> members;
  bool complete = false;
};

class Parser {
 public:
  explicit Parser(std::vector<Token> tokens, const std::string* main_file)
      : t_(std::move(tokens)), main_file_(main_file) {
    Token end;
    end.file = t_.empty() ? main_file : t_.back().file;
    end.line = t_.empty() ? 1 : t_.back().line;
    t_.push_back(end);
  }
  Status Definitions(bool in_module);
  Result<IdlMessage> Flatten(const std::string& type_name, const std::string& path) const;

 private:
  const Token& Peek(std::size_t k = 0) const { return t_[std::min(i_ + k, t_.size() - 1)]; }
  Error Fail(const std::string& what) const { return IdlError(*Peek().file, Peek().line, what); }
  bool Accept(const char* text) {
    if (Peek().kind == Token::kEnd || Peek().text != text) return false;
    ++i_;
    return true;
  }
  Status Expect(const char* text) {
    if (Accept(text)) return {};
    return Fail(std::string("expected '") + text + "', got '" + Peek().text + "'");
  }
  Result<std::string> Name();
  std::string Qualify(const std::string& name) const;
  // The qualified name `name` refers to from the current scope (IDL's scoping: innermost first),
  // among the names `known` holds; empty when none.
  template <typename Map>
  std::string Resolve(const std::string& name, const Map& known) const;
  Status Annotations(bool* refused_key);
  Status Module();
  Status Struct();
  Status Enum();
  Status Typedef();
  Status Const();
  Result<TypeRef> Type();
  Result<std::uint32_t> ConstExpr();
  Status Declarators(const TypeRef& type, std::vector<Member>* out);

  struct CLayout {
    std::uint32_t size = 0, align = 1;
  };
  CLayout StructLayout(const std::string& name) const;
  Status FlattenMembers(const std::string& struct_name, const std::string& prefix, std::uint32_t c_base,
                        IdlMessage* out, std::uint32_t* cdr, int depth) const;

  std::vector<Token> t_;
  std::size_t i_ = 0;
  const std::string* main_file_;
  std::vector<std::string> scope_;
  std::map<std::string, StructDef> structs_;
  std::map<std::string, TypeRef> typedefs_;
  std::map<std::string, bool> enums_;
  std::map<std::string, std::uint64_t> consts_;
  std::string last_main_struct_;
};

Result<std::string> Parser::Name() {
  if (Peek().kind != Token::kIdent) return Fail("expected a name, got '" + Peek().text + "'");
  return t_[i_++].text;
}

std::string Parser::Qualify(const std::string& name) const {
  std::string q;
  for (const auto& s : scope_) q += s + "::";
  return q + name;
}

template <typename Map>
std::string Parser::Resolve(const std::string& name, const Map& known) const {
  if (name.rfind("::", 0) == 0) return known.count(name.substr(2)) != 0 ? name.substr(2) : "";
  for (std::size_t n = scope_.size() + 1; n-- > 0;) {
    std::string q;
    for (std::size_t k = 0; k < n; ++k) q += scope_[k] + "::";
    if (known.count(q + name) != 0) return q + name;
  }
  return "";
}

Status Parser::Annotations(bool* refused_key) {
  while (Accept("@")) {
    auto name = Name();
    if (!name) return std::move(name).error();
    std::string args;
    if (Accept("(")) {
      for (int depth = 1; depth > 0; ++i_) {
        if (Peek().kind == Token::kEnd) return Fail("annotation @" + *name + " not closed");
        depth += Peek().text == "(" ? 1 : Peek().text == ")" ? -1 : 0;
        if (depth > 0) args += Peek().text;
      }
    }
    std::string a = *name;
    std::transform(a.begin(), a.end(), a.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    std::transform(args.begin(), args.end(), args.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (a == "appendable" || a == "mutable" || (a == "extensibility" && args != "final"))
      return Fail("@" + *name + (args.empty() ? "" : "(" + args + ")") + ": only final structs (plain CDR) are read");
    if (a == "key" || a == "optional" || a == "external") {
      if (refused_key != nullptr) *refused_key = true;
      return Fail("@" + *name + ": not supported (a message is one fixed-size sample without keys)");
    }
  }
  return {};
}

Status Parser::Definitions(bool in_module) {
  while (Peek().kind != Token::kEnd && !(in_module && Peek().text == "}")) {
    if (auto st = Annotations(nullptr); !st) return st;
    const std::string word = Peek().text;
    Status st;
    if (word == "module") {
      st = Module();
    } else if (word == "struct") {
      st = Struct();
    } else if (word == "enum") {
      st = Enum();
    } else if (word == "typedef") {
      st = Typedef();
    } else if (word == "const") {
      st = Const();
    } else if (word == ";") {
      ++i_;
    } else if (word == "union" || word == "interface" || word == "exception" || word == "bitmask" || word == "bitset") {
      return Fail("'" + word + "' is not supported (structs of fixed-size members only)");
    } else {
      return Fail("expected a module, struct, enum, typedef or const, got '" + word + "'");
    }
    if (!st) return st;
  }
  return {};
}

Status Parser::Module() {
  ++i_;  // module
  auto name = Name();
  if (!name) return std::move(name).error();
  if (auto st = Expect("{"); !st) return st;
  scope_.push_back(*name);
  if (auto st = Definitions(true); !st) return st;
  scope_.pop_back();
  if (auto st = Expect("}"); !st) return st;
  Accept(";");
  return {};
}

Status Parser::Struct() {
  ++i_;  // struct
  auto name = Name();
  if (!name) return std::move(name).error();
  const std::string q = Qualify(*name);
  if (Accept(";")) {
    structs_.try_emplace(q);  // a forward declaration
    return {};
  }
  if (Peek().text == ":") return Fail("struct " + q + ": inheritance is not supported");
  PBPPO_TRY(Expect("{"));
  StructDef& def = structs_[q];
  if (def.complete) return Fail("struct " + q + " is defined twice");
  std::vector<Member> members;
  while (!Accept("}")) {
    if (Peek().kind == Token::kEnd) return Fail("struct " + q + " not closed");
    PBPPO_TRY(Annotations(nullptr));
    auto type = Type();
    if (!type) return std::move(type).error();
    PBPPO_TRY(Declarators(*type, &members));
  }
  PBPPO_TRY(Expect(";"));
  if (members.empty()) return Fail("struct " + q + " has no members");
  for (std::size_t a = 0; a < members.size(); ++a)
    for (std::size_t b = a + 1; b < members.size(); ++b)
      if (members[a].name == members[b].name)
        return IdlError(*members[b].file, members[b].line, "struct " + q + ": member '" + members[b].name + "' twice");
  def.members = std::move(members);
  def.complete = true;
  if (t_[i_ - 1].file == main_file_) last_main_struct_ = q;
  return {};
}

Status Parser::Enum() {
  ++i_;  // enum
  auto name = Name();
  if (!name) return std::move(name).error();
  PBPPO_TRY(Expect("{"));
  int enumerators = 0;
  while (!Accept("}")) {
    if (Peek().kind == Token::kEnd) return Fail("enum " + *name + " not closed");
    PBPPO_TRY(Annotations(nullptr));
    auto e = Name();
    if (!e) return std::move(e).error();
    ++enumerators;
    if (!Accept(",") && Peek().text != "}") return Fail("enum " + *name + ": expected ',' or '}'");
  }
  PBPPO_TRY(Expect(";"));
  if (enumerators == 0) return Fail("enum " + *name + " has no enumerators");
  enums_[Qualify(*name)] = true;
  return {};
}

Status Parser::Typedef() {
  ++i_;  // typedef
  auto type = Type();
  if (!type) return std::move(type).error();
  std::vector<Member> names;
  PBPPO_TRY(Declarators(*type, &names));
  for (const Member& m : names) typedefs_[Qualify(m.name)] = m.type;
  return {};
}

Status Parser::Const() {
  ++i_;  // const
  const bool integer = Peek().text != "float" && Peek().text != "double" && Peek().text != "string" &&
                       Peek().text != "char" && Peek().text != "boolean";
  while (Peek().kind != Token::kEnd && Peek().text != "=") ++i_;  // the type, then the name
  const std::string name = t_[i_ - 1].text;
  PBPPO_TRY(Expect("="));
  if (!integer) {
    while (Peek().kind != Token::kEnd && Peek().text != ";") ++i_;
    return Expect(";");
  }
  auto v = ConstExpr();
  if (!v) return std::move(v).error();
  consts_[Qualify(name)] = *v;
  return Expect(";");
}

Result<std::uint32_t> Parser::ConstExpr() {
  // Sums and products of integer literals and constants, left to right within each level. Every
  // value on the way stays within 32 bits, so that no step can wrap.
  constexpr std::uint64_t kMax = 0xffffffffull;
  auto too_large = [&](const std::string& v) { return Fail("constant " + v + " is too large"); };
  auto factor = [&](std::uint64_t* out) -> Status {
    const Token& t = Peek();
    if (t.kind == Token::kNumber) {
      char* end = nullptr;
      errno = 0;
      const unsigned long long v = std::strtoull(t.text.c_str(), &end, 0);
      if (*end != '\0') return IdlError(*t.file, t.line, "'" + t.text + "' is not a whole number");
      if (errno == ERANGE || v > kMax) return too_large(t.text);
      ++i_;
      *out = v;
      return {};
    }
    if (t.kind == Token::kIdent) {
      const std::string q = Resolve(t.text, consts_);
      if (q.empty()) return IdlError(*t.file, t.line, "'" + t.text + "' is not an integer constant");
      ++i_;
      *out = consts_.at(q);
      return {};
    }
    return IdlError(*t.file, t.line, "expected a number, got '" + t.text + "'");
  };
  auto term = [&](std::uint64_t* out) -> Status {
    PBPPO_TRY(factor(out));
    while (Peek().text == "*" || Peek().text == "/") {
      const bool times = t_[i_++].text == "*";
      std::uint64_t w = 0;
      PBPPO_TRY(factor(&w));
      if (!times && w == 0) return Fail("division by zero");
      *out = times ? *out * w : *out / w;  // both within 32 bits: the product fits in 64
      if (*out > kMax) return too_large(std::to_string(*out));
    }
    return {};
  };
  std::uint64_t v = 0;
  PBPPO_TRY(term(&v));
  while (Peek().text == "+" || Peek().text == "-") {
    const bool plus = t_[i_++].text == "+";
    std::uint64_t w = 0;
    PBPPO_TRY(term(&w));
    if (!plus && w > v) return Fail("negative constant");
    v = plus ? v + w : v - w;
    if (v > kMax) return too_large(std::to_string(v));
  }
  return static_cast<std::uint32_t>(v);
}

Result<TypeRef> Parser::Type() {
  static const std::map<std::string, IdlScalar> kScalars = {
      {"boolean", IdlScalar::kBool},  {"char", IdlScalar::kChar},     {"octet", IdlScalar::kUint8},
      {"int8", IdlScalar::kInt8},     {"uint8", IdlScalar::kUint8},   {"int16", IdlScalar::kInt16},
      {"uint16", IdlScalar::kUint16}, {"int32", IdlScalar::kInt32},   {"uint32", IdlScalar::kUint32},
      {"int64", IdlScalar::kInt64},   {"uint64", IdlScalar::kUint64}, {"float", IdlScalar::kFloat},
      {"double", IdlScalar::kDouble}, {"short", IdlScalar::kInt16}};
  TypeRef t;
  const Token& w = Peek();
  if (w.kind != Token::kIdent) return Fail("expected a type, got '" + w.text + "'");
  if (w.text == "unsigned") {
    ++i_;
    if (Accept("short")) {
      t.scalar = IdlScalar::kUint16;
    } else if (Accept("long")) {
      t.scalar = Accept("long") ? IdlScalar::kUint64 : IdlScalar::kUint32;
    } else {
      return Fail("'unsigned " + Peek().text + "' is not a type");
    }
    return t;
  }
  if (w.text == "long") {
    ++i_;
    if (Peek().text == "double") return Fail("long double is not supported");
    t.scalar = Accept("long") ? IdlScalar::kInt64 : IdlScalar::kInt32;
    return t;
  }
  // string<N>, sequence<T, N>: the bound, a positive constant.
  auto bound = [&](const std::string& what) -> Status {
    auto n = ConstExpr();
    if (!n) return std::move(n).error();
    if (*n == 0) return Fail(what + " bounded to 0");
    t.bound = *n;
    return {};
  };
  if (w.text == "string") {
    ++i_;
    t.is_string = true;
    if (Accept("<")) {
      PBPPO_TRY(bound("string"));
      PBPPO_TRY(Expect(">"));
    }
    return t;
  }
  if (w.text == "sequence") {
    ++i_;
    PBPPO_TRY(Expect("<"));
    const Token& e = Peek();
    auto element = Type();
    if (!element) return std::move(element).error();
    if (element->is_struct || element->is_string || element->is_sequence || !element->dims.empty())
      return IdlError(*e.file, e.line,
                      "sequence<" + e.text +
                          ">: only sequences of primitives are read (not of structs, strings, "
                          "sequences or arrays)");
    t.is_sequence = true;
    t.scalar = element->scalar;
    if (Accept(",")) PBPPO_TRY(bound("sequence"));
    PBPPO_TRY(Expect(">"));
    return t;
  }
  for (const char* v : {"wstring", "map", "wchar", "any", "fixed", "Object", "ValueBase"})
    if (w.text == v) return Fail(std::string(v) + " is not supported (primitives, structs, strings and sequences)");
  if (const auto it = kScalars.find(w.text); it != kScalars.end()) {
    ++i_;
    t.scalar = it->second;
    return t;
  }
  if (std::string q = Resolve(w.text, typedefs_); !q.empty()) {
    ++i_;
    return typedefs_.at(q);
  }
  if (std::string q = Resolve(w.text, enums_); !q.empty()) {
    ++i_;
    t.scalar = IdlScalar::kUint32;
    return t;
  }
  if (std::string q = Resolve(w.text, structs_); !q.empty()) {
    if (!structs_.at(q).complete) return Fail("struct " + q + " is declared but not defined before this use");
    ++i_;
    t.is_struct = true;
    t.name = q;
    return t;
  }
  return Fail("unknown type '" + w.text + "'");
}

Status Parser::Declarators(const TypeRef& type, std::vector<Member>* out) {
  do {
    Member m;
    m.file = Peek().file;
    m.line = Peek().line;
    auto name = Name();
    if (!name) return std::move(name).error();
    m.name = *name;
    m.type = type;
    std::vector<std::uint32_t> dims;
    std::uint64_t count = 1;
    for (const std::uint32_t d : type.dims) count *= d;
    while (Accept("[")) {
      auto n = ConstExpr();
      if (!n) return std::move(n).error();
      if (*n == 0) return Fail("member '" + m.name + "': an array of 0 elements");
      dims.push_back(*n);
      count *= *n;
      if (count > kMaxArray) return Fail("member '" + m.name + "': more than 65536 elements");
      PBPPO_TRY(Expect("]"));
    }
    dims.insert(dims.end(), type.dims.begin(), type.dims.end());
    m.type.dims = std::move(dims);
    out->push_back(std::move(m));
  } while (Accept(","));
  return Expect(";");
}

Parser::CLayout Parser::StructLayout(const std::string& name) const {
  CLayout s;
  for (const Member& m : structs_.at(name).members) {
    // A string or sequence has no fixed place in memory: the message has no C layout (c_size 0).
    const CLayout e = m.type.is_struct ? StructLayout(m.type.name)
                      : m.type.is_string || m.type.is_sequence
                          ? CLayout{8, 8}
                          : CLayout{IdlScalarSize(m.type.scalar), IdlScalarSize(m.type.scalar)};
    std::uint32_t count = 1;
    for (const std::uint32_t d : m.type.dims) count *= d;
    s.size = (s.size + e.align - 1) / e.align * e.align + e.size * count;
    s.align = std::max(s.align, e.align);
  }
  s.size = (s.size + s.align - 1) / s.align * s.align;
  return s;
}

Status Parser::FlattenMembers(const std::string& struct_name, const std::string& prefix, std::uint32_t c_base,
                              IdlMessage* out, std::uint32_t* cdr, int depth) const {
  std::uint32_t c = 0;
  for (const Member& m : structs_.at(struct_name).members) {
    if (depth >= kMaxDepth) return IdlError(*m.file, m.line, "member '" + m.name + "' nests deeper than 16 structs");
    const bool variable = m.type.is_string || m.type.is_sequence;
    const CLayout e = m.type.is_struct ? StructLayout(m.type.name)
                      : variable       ? CLayout{8, 8}
                                       : CLayout{IdlScalarSize(m.type.scalar), IdlScalarSize(m.type.scalar)};
    std::uint32_t count = 1;
    for (const std::uint32_t d : m.type.dims) count *= d;
    c = (c + e.align - 1) / e.align * e.align;
    for (std::uint32_t k = 0; k < count; ++k) {
      std::string path = prefix + m.name;
      std::vector<std::uint32_t> index(m.type.dims.size());
      for (std::uint32_t rest = k, d = static_cast<std::uint32_t>(m.type.dims.size()); d-- > 0;) {
        index[d] = rest % m.type.dims[d];
        rest /= m.type.dims[d];
      }
      for (const std::uint32_t i : index) path.append("[").append(std::to_string(i)).append("]");
      const std::uint32_t at = c_base + c + k * e.size;
      if (m.type.is_struct) {
        PBPPO_TRY(FlattenMembers(m.type.name, path + ".", at, out, cdr, depth + 1));
        continue;
      }
      if (variable) {
        // Its length (and a string's NUL) in the layout; laid out again at the end.
        IdlItem item;
        item.kind = m.type.is_string ? IdlItem::Kind::kString : IdlItem::Kind::kSequence;
        item.path = std::move(path);
        item.element = m.type.scalar;
        item.bound = m.type.bound;
        out->items.push_back(std::move(item));
        *cdr = (*cdr + 3u) / 4u * 4u + 5u;
        if (*cdr > kMaxCdrBytes || out->items.size() > kMaxLeaves)
          return IdlError(*m.file, m.line,
                          "member '" + m.name + "': the message exceeds 65536 bytes or 16384 primitives");
        continue;
      }
      const std::uint32_t size = IdlScalarSize(m.type.scalar);
      *cdr = (*cdr + size - 1) / size * size;
      IdlItem item;
      item.leaf = static_cast<std::uint32_t>(out->leaves.size());
      out->items.push_back(std::move(item));
      out->leaves.push_back({std::move(path), m.type.scalar, *cdr, at});
      *cdr += size;
      if (*cdr > kMaxCdrBytes || out->leaves.size() > kMaxLeaves)
        return IdlError(*m.file, m.line,
                        "member '" + m.name + "': the message exceeds 65536 bytes or 16384 primitives");
    }
    c += e.size * count;
  }
  return {};
}

Result<IdlMessage> Parser::Flatten(const std::string& type_name, const std::string& path) const {
  const std::string file = std::filesystem::path(path).filename().string();
  std::string name = type_name.rfind("::", 0) == 0 ? type_name.substr(2) : type_name;
  if (name.empty()) name = last_main_struct_;
  const auto it = structs_.find(name);
  if (it == structs_.end() || !it->second.complete) {
    std::string known;
    for (const auto& [n, def] : structs_)
      if (def.complete) known += (known.empty() ? "" : ", ") + n;
    return MakeError(ErrorCode::kMismatch,
                     file + ": " +
                         (name.empty() ? std::string("defines no struct")
                                       : "no struct '" + name + "' (known: " + (known.empty() ? "none" : known) + ")"));
  }
  IdlMessage m;
  m.type_name = name;
  m.file = path;
  std::uint32_t cdr = 0;
  PBPPO_TRY(FlattenMembers(name, "", 0, &m, &cdr, 0));
  m.cdr_size = cdr;
  m.c_size = StructLayout(name).size;
  if (std::none_of(m.items.begin(), m.items.end(), [](const IdlItem& i) { return i.kind != IdlItem::Kind::kLeaf; })) {
    m.items.clear();  // one fixed size: the leaves are the layout
  } else {
    m.c_size = 0;
    for (IdlLeaf& l : m.leaves) l.c_offset = 0;
    if (!LayOut(&m))  // every sequence empty until the robot file names its elements
      return MakeError(ErrorCode::kInvalidValue, file + ": " + name + " exceeds 65536 bytes");
  }
  return m;
}

}  // namespace

std::uint32_t IdlScalarSize(IdlScalar type) noexcept {
  switch (type) {
    case IdlScalar::kBool:
    case IdlScalar::kChar:
    case IdlScalar::kInt8:
    case IdlScalar::kUint8: return 1;
    case IdlScalar::kInt16:
    case IdlScalar::kUint16: return 2;
    case IdlScalar::kInt32:
    case IdlScalar::kUint32:
    case IdlScalar::kFloat: return 4;
    case IdlScalar::kInt64:
    case IdlScalar::kUint64:
    case IdlScalar::kDouble: return 8;
  }
  return 8;
}

std::uint32_t IdlCounterMask(IdlScalar type) noexcept {
  switch (type) {
    case IdlScalar::kUint8: return 0xffu;
    case IdlScalar::kUint16: return 0xffffu;
    case IdlScalar::kUint32: return 0xffffffffu;
    default: return 0;
  }
}

const char* ToString(IdlScalar type) noexcept {
  switch (type) {
    case IdlScalar::kBool: return "boolean";
    case IdlScalar::kChar: return "char";
    case IdlScalar::kInt8: return "int8";
    case IdlScalar::kUint8: return "uint8";
    case IdlScalar::kInt16: return "int16";
    case IdlScalar::kUint16: return "uint16";
    case IdlScalar::kInt32: return "int32";
    case IdlScalar::kUint32: return "uint32";
    case IdlScalar::kInt64: return "int64";
    case IdlScalar::kUint64: return "uint64";
    case IdlScalar::kFloat: return "float";
    case IdlScalar::kDouble: return "double";
  }
  return "?";
}

int IdlMessage::LeafIndex(std::string_view path) const noexcept {
  for (std::size_t i = 0; i < leaves.size(); ++i)
    if (leaves[i].path == path) return static_cast<int>(i);
  return -1;
}

int IdlMessage::Element(std::string_view path) {
  if (const int k = LeafIndex(path); k >= 0 || items.empty()) return k;
  const std::size_t open = path.rfind('[');
  if (open == std::string_view::npos || path.back() != ']' || path.size() - open < 3 || path.size() - open > 7)
    return -1;
  std::uint32_t index = 0;
  for (const char c : path.substr(open + 1, path.size() - open - 2)) {
    if (c < '0' || c > '9') return -1;
    index = index * 10 + static_cast<std::uint32_t>(c - '0');
  }
  const auto it = std::find_if(items.begin(), items.end(), [&](const IdlItem& i) {
    return i.kind == IdlItem::Kind::kSequence && i.path == path.substr(0, open);
  });
  if (it == items.end() || (it->bound != 0 && index >= it->bound) || index >= kMaxArray ||
      leaves.size() + (index + 1 - it->elements.size()) > kMaxLeaves)
    return -1;
  const std::size_t had = it->elements.size();
  while (it->elements.size() <= index) {
    it->elements.push_back(static_cast<std::uint32_t>(leaves.size()));
    std::string name = it->path;
    name += "[";
    name += std::to_string(it->elements.size() - 1);
    name += "]";
    leaves.push_back({std::move(name), it->element, 0, 0});
  }
  if (!LayOut(this)) {  // too large: as it was
    leaves.resize(leaves.size() - (it->elements.size() - had));
    it->elements.resize(had);
    LayOut(this);
    return -1;
  }
  return static_cast<int>(it->elements.back());
}

Result<IdlMessage> ParseIdlMessage(const std::string& text, const std::string& path, const std::string& type_name,
                                   const IdlFileReader& read) {
  Lexer lexer(read);
  PBPPO_TRY(lexer.Add(text, path, 0));
  Parser parser(std::move(lexer.tokens), lexer.main_file());
  PBPPO_TRY(parser.Definitions(false));
  return parser.Flatten(type_name, path);
}

}  // namespace pbppo::robot
