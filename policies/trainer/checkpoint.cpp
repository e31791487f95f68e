#include "policies/trainer/checkpoint.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <span>

#include "policies/trainer/state_io.hpp"
#include "runtime/policy/blob.hpp"

namespace pbppo::trainer {
namespace {

constexpr char kMagic[12] = {'P', 'B', 'P', 'P', 'O', '-', 'R', 'E', 'S', 'U', 'M', 'E'};
constexpr std::uint32_t kVersion = 1;

std::uint64_t Fnv1a(const char* p, std::size_t n) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(p[i]);
    h *= 0x100000001b3ull;
  }
  return h;
}

}  // namespace

Status WriteResumeFile(const std::string& path, const ResumeFile& f) {
  ByteWriter w;
  w.Put(kMagic, sizeof kMagic);
  w.Put(kVersion);
  w.Put(static_cast<std::uint64_t>(f.args.size()));
  for (const std::string& a : f.args) w.PutString(a);
  w.PutString(f.git_revision);
  w.PutVector(f.state);
  w.Put(Fnv1a(w.bytes().data(), w.bytes().size()));
  const std::vector<char>& b = w.bytes();
  return policy::WriteFileAtomic(path, std::span(reinterpret_cast<const std::uint8_t*>(b.data()), b.size()));
}

Result<ResumeFile> ReadResumeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return MakeError(ErrorCode::kIo, "'" + path + "': cannot be read (" + std::strerror(errno) + ")");
  const std::vector<char> b{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  auto bad = [&](const std::string& what) { return MakeError(ErrorCode::kFormat, "'" + path + "': " + what); };
  if (b.size() < sizeof kMagic + 4 + 8 || std::memcmp(b.data(), kMagic, sizeof kMagic) != 0)
    return bad("not a resume file (no PBPPO-RESUME header)");
  std::uint32_t version = 0;
  std::memcpy(&version, b.data() + sizeof kMagic, sizeof version);
  if (version != kVersion)
    return bad("version " + std::to_string(version) + ", this build reads version " + std::to_string(kVersion));
  std::uint64_t hash = 0;
  std::memcpy(&hash, b.data() + b.size() - sizeof hash, sizeof hash);
  if (hash != Fnv1a(b.data(), b.size() - sizeof hash)) return bad("damaged (its checksum does not match)");
  try {
    ByteReader r(b.data(), b.size() - sizeof hash, "'" + path + "'");
    char magic[sizeof kMagic];
    r.Get(magic, sizeof magic, "the header");
    (void)r.Get<std::uint32_t>("the version");
    ResumeFile f;
    f.args.resize(static_cast<std::size_t>(r.Get<std::uint64_t>("the argument count")));
    if (f.args.size() > b.size()) return bad("an argument count of " + std::to_string(f.args.size()));
    for (std::string& a : f.args) a = r.GetString("an argument");
    f.git_revision = r.GetString("the git revision");
    r.GetVector(f.state, "the state");
    r.CheckEnd();
    return f;
  } catch (const std::exception& e) {
    return MakeError(ErrorCode::kFormat, e.what());
  }
}

}  // namespace pbppo::trainer
