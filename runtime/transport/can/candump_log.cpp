#include "runtime/transport/can/candump_log.hpp"

#include <cerrno>
#include <chrono>
#include <cstring>

namespace pbppo::can {
namespace {

constexpr char kHex[] = "0123456789ABCDEF";
constexpr std::uint32_t kErrFlag = 0x20000000u;  // CAN_ERR_FLAG as candump prints it

int HexValue(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

bool ParseHex(std::string_view s, std::uint64_t* out) noexcept {
  if (s.empty() || s.size() > 16) return false;
  std::uint64_t v = 0;
  for (char c : s) {
    const int h = HexValue(c);
    if (h < 0) return false;
    v = (v << 4u) | static_cast<std::uint64_t>(h);
  }
  *out = v;
  return true;
}

bool ParseDigits(std::string_view s, std::uint64_t* out) noexcept {
  if (s.empty() || s.size() > 19) return false;
  std::uint64_t v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + static_cast<std::uint64_t>(c - '0');
  }
  *out = v;
  return true;
}

}  // namespace

std::size_t FormatCandumpLine(std::uint64_t time_ns, std::string_view iface, const CanFrame& f, char* out,
                              std::size_t size) noexcept {
  if (size < kCandumpLineMax || iface.size() > 15) return 0;
  const std::uint64_t sec = time_ns / 1000000000ull;
  const std::uint64_t usec = (time_ns % 1000000000ull) / 1000ull;
  int w = std::snprintf(out, size, "(%llu.%06llu) %.*s ", static_cast<unsigned long long>(sec),
                        static_cast<unsigned long long>(usec), static_cast<int>(iface.size()), iface.data());
  if (w < 0) return 0;
  auto n = static_cast<std::size_t>(w);
  if ((f.flags & kFlagError) != 0) {
    n += static_cast<std::size_t>(std::snprintf(out + n, size - n, "%08X#", (f.id & 0x1FFFFFFFu) | kErrFlag));
  } else if ((f.flags & kFlagExtended) != 0) {
    n += static_cast<std::size_t>(std::snprintf(out + n, size - n, "%08X#", f.id & kExtendedIdMask));
  } else {
    n += static_cast<std::size_t>(std::snprintf(out + n, size - n, "%03X#", f.id & kStandardIdMask));
  }
  const std::uint8_t max_len = (f.flags & kFlagFd) != 0 ? kFdMaxLen : kClassicMaxLen;
  const std::uint8_t len = f.len < max_len ? f.len : max_len;
  if ((f.flags & kFlagFd) != 0) {
    out[n++] = '#';
    out[n++] = kHex[((f.flags & kFlagBrs) != 0 ? 1 : 0) | ((f.flags & kFlagEsi) != 0 ? 2 : 0)];
  } else if ((f.flags & kFlagRtr) != 0) {
    out[n++] = 'R';
  }
  if ((f.flags & kFlagRtr) == 0 || (f.flags & kFlagFd) != 0) {
    for (std::uint8_t i = 0; i < len; ++i) {
      out[n++] = kHex[f.data[i] >> 4u];
      out[n++] = kHex[f.data[i] & 0xFu];
    }
  }
  out[n++] = '\n';
  out[n] = '\0';
  return n;
}

bool ParseCandumpLine(std::string_view line, CandumpRecord* out) noexcept {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.remove_suffix(1);
  if (line.size() < 4 || line.front() != '(') return false;
  const std::size_t close = line.find(')');
  if (close == std::string_view::npos) return false;
  const std::string_view stamp = line.substr(1, close - 1);
  const std::size_t dot = stamp.find('.');
  if (dot == std::string_view::npos) return false;
  std::uint64_t sec = 0, frac = 0;
  const std::string_view frac_s = stamp.substr(dot + 1);
  if (!ParseDigits(stamp.substr(0, dot), &sec) || !ParseDigits(frac_s, &frac) || frac_s.size() > 9) return false;
  for (std::size_t i = frac_s.size(); i < 9; ++i) frac *= 10;
  if (sec > 18000000000ull) return false;
  CandumpRecord r;
  r.time_ns = sec * 1000000000ull + frac;
  std::string_view rest = line.substr(close + 1);
  if (rest.empty() || rest.front() != ' ') return false;
  rest.remove_prefix(1);
  const std::size_t sp = rest.find(' ');
  if (sp == std::string_view::npos || sp == 0 || sp > 15) return false;
  for (std::size_t i = 0; i < sp; ++i) {
    if (rest[i] < 0x21 || rest[i] > 0x7E) return false;  // interface names are printable ASCII
  }
  std::memcpy(r.iface, rest.data(), sp);
  r.iface[sp] = '\0';
  rest.remove_prefix(sp + 1);
  const std::size_t hash = rest.find('#');
  if (hash == std::string_view::npos) return false;
  const std::string_view id_s = rest.substr(0, hash);
  std::uint64_t id = 0;
  if (!ParseHex(id_s, &id)) return false;
  CanFrame& f = r.frame;
  f.timestamp_ns = r.time_ns;
  if (id_s.size() == 3) {
    if (id > kStandardIdMask) return false;
    f.id = static_cast<std::uint32_t>(id);
  } else if (id_s.size() == 8) {
    if ((id & kErrFlag) != 0) {
      f.flags |= kFlagError;
      f.id = static_cast<std::uint32_t>(id & 0x1FFFFFFFu);
    } else if (id <= kExtendedIdMask) {
      f.flags |= kFlagExtended;
      f.id = static_cast<std::uint32_t>(id);
    } else {
      return false;
    }
  } else {
    return false;
  }
  std::string_view data = rest.substr(hash + 1);
  std::uint8_t max_len = kClassicMaxLen;
  if (!data.empty() && data.front() == '#') {
    if (data.size() < 2) return false;
    const int fl = HexValue(data[1]);
    if (fl < 0 || fl > 3) return false;
    f.flags |= kFlagFd;
    if ((fl & 1) != 0) f.flags |= kFlagBrs;
    if ((fl & 2) != 0) f.flags |= kFlagEsi;
    data.remove_prefix(2);
    max_len = kFdMaxLen;
  } else if (!data.empty() && data.front() == 'R') {
    f.flags |= kFlagRtr;
    data.remove_prefix(1);
    if (!data.empty()) {
      // candump prints a DLC digit after R for remote requests with a length
      const int dlc = HexValue(data.front());
      if (data.size() != 1 || dlc < 0 || dlc > 8) return false;
      f.len = static_cast<std::uint8_t>(dlc);
    }
    *out = r;
    return true;
  }
  if (data.size() % 2 != 0 || data.size() / 2 > max_len) return false;
  f.len = static_cast<std::uint8_t>(data.size() / 2);
  if ((f.flags & kFlagFd) != 0 && !IsValidFdLength(f.len)) return false;
  for (std::size_t i = 0; i < f.len; ++i) {
    const int hi = HexValue(data[2 * i]), lo = HexValue(data[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    f.data[i] = static_cast<std::uint8_t>((hi << 4) | lo);
  }
  *out = r;
  return true;
}

Result<std::unique_ptr<CandumpLogger>> CandumpLogger::Open(const std::string& path, std::vector<std::string> interfaces,
                                                           std::size_t queue_capacity) {
  for (const std::string& i : interfaces) {
    if (i.empty() || i.size() > 15 || i.find(' ') != std::string::npos)
      return MakeError(ErrorCode::kInvalidValue,
                       "candump log: interface name '" + i + "' is empty, too long or has a space");
  }
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return MakeError(ErrorCode::kIo, "candump log: " + path + ": " + std::strerror(errno));
  std::unique_ptr<CandumpLogger> l(new CandumpLogger(f, std::move(interfaces), queue_capacity));
  l->thread_ = std::thread([p = l.get()] { p->Run(); });
  return l;
}

CandumpLogger::CandumpLogger(std::FILE* file, std::vector<std::string> interfaces, std::size_t capacity)
    : file_(file), interfaces_(std::move(interfaces)), queue_(capacity) {}

CandumpLogger::~CandumpLogger() {
  Stop();
}

bool CandumpLogger::Push(std::uint32_t bus, const CanFrame& frame) noexcept {
  return queue_.TryPush(Item{bus, frame});
}

std::size_t CandumpLogger::DrainOnce() {
  Item it;
  char line[kCandumpLineMax];
  std::size_t n = 0;
  while (queue_.TryPop(&it)) {
    const std::string_view iface = it.bus < interfaces_.size() ? std::string_view(interfaces_[it.bus]) : "?";
    const std::size_t len = FormatCandumpLine(it.frame.timestamp_ns, iface, it.frame, line, sizeof line);
    if (len == 0 || std::fwrite(line, 1, len, file_) != len) {
      write_errors_.fetch_add(1, std::memory_order_relaxed);
    } else {
      written_.fetch_add(1, std::memory_order_relaxed);
    }
    ++n;
  }
  return n;
}

void CandumpLogger::Run() {
  while (!stop_.load(std::memory_order_acquire)) {
    if (DrainOnce() == 0) {
      std::fflush(file_);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  DrainOnce();
}

void CandumpLogger::Stop() {
  if (thread_.joinable()) {
    stop_.store(true, std::memory_order_release);
    thread_.join();
  }
  if (file_ != nullptr) {
    if (std::fclose(file_) != 0) write_errors_.fetch_add(1, std::memory_order_relaxed);
    file_ = nullptr;
  }
}

}  // namespace pbppo::can
