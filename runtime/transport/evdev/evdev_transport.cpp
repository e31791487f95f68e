#include "runtime/transport/evdev/evdev_transport.hpp"

#include <fcntl.h>
#include <linux/input.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include "runtime/robot/input_codes.hpp"

namespace pbppo::evdev {

static_assert(sizeof(input_event) == sizeof(EventRecord), "a 64-bit input_event");

Status WriteEventFile(const std::string& path, const std::vector<EventRecord>& records) {
  const std::string tmp = path + ".part";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    for (const EventRecord& r : records) out.write(reinterpret_cast<const char*>(&r), sizeof r);
    if (!out.flush()) return MakeError(ErrorCode::kIo, tmp + ": cannot write the event file");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) return MakeError(ErrorCode::kIo, path + ": cannot rename " + tmp);
  return {};
}

Result<std::unique_ptr<EvdevTransport>> EvdevTransport::Open(const robot::RobotModel& model,
                                                             const std::string& transport,
                                                             const EvdevOptions& options) {
  const int t = model.TransportIndex(transport);
  if (t < 0 || model.transports[static_cast<std::size_t>(t)].kind != "evdev")
    return MakeError(ErrorCode::kInvalidValue, model.path + ": no evdev transport '" + transport + "'");
  std::unique_ptr<EvdevTransport> e(new EvdevTransport());
  e->model_ = &model;
  e->spec_ = model.transports[static_cast<std::size_t>(t)].evdev;
  if (!options.device.empty()) e->spec_.device = options.device;
  const robot::StreamSpec& s = model.streams[e->spec_.stream];
  e->first_field_ = s.first_field;
  e->field_count_ = s.field_count;
  e->tick_s_ = model.tick_period_s;
  e->reopen_ticks_ =
      std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::llround(e->spec_.reopen_s / e->tick_s_)));
  e->axis_value_.assign(e->spec_.axes.size(), 0);
  for (std::size_t i = 0; i < e->spec_.axes.size(); ++i) {
    // Centred until the device says otherwise.
    const robot::EvdevAxisSpec& a = e->spec_.axes[i];
    e->axis_value_[i] = static_cast<std::int32_t>(std::floor((a.shape.raw_min + a.shape.raw_max) / 2));
  }
  e->axis_pending_ = e->axis_value_;
  e->button_value_.assign(e->spec_.buttons.size(), 0);
  e->button_pending_ = e->button_value_;
  e->out_.assign(e->field_count_, 0.0);
  struct stat st{};
  if (::stat(e->spec_.device.c_str(), &st) == 0 && S_ISREG(st.st_mode)) {
    const std::string& path = e->spec_.device;
    if (st.st_size % static_cast<off_t>(sizeof(EventRecord)) != 0)
      return MakeError(ErrorCode::kInvalidValue, model.path + ": transport '" + transport + "': event file " + path +
                                                     " has " + std::to_string(st.st_size) +
                                                     " bytes, not a whole number of 24-byte event records");
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof())
      return MakeError(ErrorCode::kIo, model.path + ": transport '" + transport + "': cannot read " + path);
    if (bytes.empty())
      return MakeError(ErrorCode::kInvalidValue,
                       model.path + ": transport '" + transport + "': event file " + path + " holds no event");
    e->file_.resize(bytes.size() / sizeof(EventRecord));
    std::memcpy(e->file_.data(), bytes.data(), bytes.size());
    constexpr std::int64_t kMaxSec = 1'000'000'000'000;  // 31,700 years: differences cannot overflow
    for (std::size_t i = 0; i < e->file_.size(); ++i) {
      const EventRecord &a = e->file_[i > 0 ? i - 1 : 0], &b = e->file_[i];
      if (b.sec < 0 || b.sec > kMaxSec || b.usec < 0 || b.usec >= 1000000 || b.sec < a.sec ||
          (b.sec == a.sec && b.usec < a.usec))
        return MakeError(ErrorCode::kInvalidValue, model.path + ": transport '" + transport + "': event file " + path +
                                                       ": record " + std::to_string(i) + " has time " +
                                                       std::to_string(b.sec) + " s " + std::to_string(b.usec) +
                                                       " us, before the one before it or not a time (0 to 10^12 s)");
    }
    e->is_file_ = true;
    e->file_open_ = true;
    ++e->stats_.opens;
  }
  return e;
}

EvdevTransport::~EvdevTransport() {
  if (fd_ >= 0) ::close(fd_);
}

void EvdevTransport::TryOpen(std::uint64_t tick) noexcept {
  next_open_tick_ = tick + reopen_ticks_;
  const int fd = ::open(spec_.device.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return;
  for (const robot::EvdevAxisSpec& a : spec_.axes) {
    input_absinfo info{};
    const bool ok = ::ioctl(fd, EVIOCGABS(static_cast<unsigned>(a.code)), &info) == 0;
    if (!ok || info.minimum != static_cast<std::int32_t>(a.shape.raw_min) ||
        info.maximum != static_cast<std::int32_t>(a.shape.raw_max)) {
      const char* name = robot::InputCodeName(robot::InputCodeKind::kAxis, a.code);
      if (ok) {
        std::snprintf(refusal_, sizeof refusal_, "%s: axis %s has range [%d, %d], the robot file says [%.0f, %.0f]",
                      spec_.device.c_str(), name, info.minimum, info.maximum, a.shape.raw_min, a.shape.raw_max);
      } else {
        std::snprintf(refusal_, sizeof refusal_, "%s: has no axis %s (%s)", spec_.device.c_str(), name,
                      std::strerror(errno));
      }
      ++stats_.refused;
      ::close(fd);
      return;
    }
  }
  fd_ = fd;
  ++stats_.opens;
  Resync();
}

void EvdevTransport::Lose() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  file_open_ = false;
  ++stats_.losses;
  lost_sample_due_ = true;
  discard_ = false;
  for (std::size_t i = 0; i < spec_.axes.size(); ++i) {
    const robot::EvdevAxisSpec& a = spec_.axes[i];
    axis_value_[i] = axis_pending_[i] = static_cast<std::int32_t>(std::floor((a.shape.raw_min + a.shape.raw_max) / 2));
  }
  std::fill(button_value_.begin(), button_value_.end(), std::uint8_t{0});
  std::fill(button_pending_.begin(), button_pending_.end(), std::uint8_t{0});
}

void EvdevTransport::Resync() noexcept {
  if (fd_ >= 0) {
    for (std::size_t i = 0; i < spec_.axes.size(); ++i) {
      input_absinfo info{};
      if (::ioctl(fd_, EVIOCGABS(static_cast<unsigned>(spec_.axes[i].code)), &info) == 0) axis_pending_[i] = info.value;
    }
    std::uint8_t keys[KEY_MAX / 8 + 1] = {};
    if (::ioctl(fd_, EVIOCGKEY(sizeof keys), keys) >= 0) {
      for (std::size_t i = 0; i < spec_.buttons.size(); ++i) {
        const int c = spec_.buttons[i].code;
        const auto bit = static_cast<unsigned>(c);
        button_pending_[i] = static_cast<std::uint8_t>((static_cast<unsigned>(keys[bit / 8]) >> (bit % 8)) & 1u);
      }
    }
  }
  std::copy(axis_pending_.begin(), axis_pending_.end(), axis_value_.begin());
  std::copy(button_pending_.begin(), button_pending_.end(), button_value_.begin());
}

void EvdevTransport::Apply(const EventRecord& e) noexcept {
  if (e.type == EV_SYN) {
    if (e.code == SYN_DROPPED) {  // the report in progress is lost, and what follows up to the next report
      ++stats_.dropped;
      discard_ = true;
      std::copy(axis_value_.begin(), axis_value_.end(), axis_pending_.begin());
      std::copy(button_value_.begin(), button_value_.end(), button_pending_.begin());
    } else if (e.code == SYN_REPORT) {
      if (discard_) {
        discard_ = false;
        Resync();  // a device says its state; a recorded file cannot: the last report's stays
      } else {
        std::copy(axis_pending_.begin(), axis_pending_.end(), axis_value_.begin());
        std::copy(button_pending_.begin(), button_pending_.end(), button_value_.begin());
      }
      ++stats_.reports;
    }
    return;
  }
  if (e.type != EV_ABS && e.type != EV_KEY) return;  // EV_MSC scan codes and the like
  if (discard_) return;
  if (e.type == EV_ABS) {
    for (std::size_t i = 0; i < spec_.axes.size(); ++i) {
      if (spec_.axes[i].code != e.code) continue;
      axis_pending_[i] = e.value;
      ++stats_.events;
      return;
    }
  } else {
    for (std::size_t i = 0; i < spec_.buttons.size(); ++i) {
      if (spec_.buttons[i].code != e.code) continue;
      button_pending_[i] = e.value != 0 ? 1 : 0;  // 2: auto-repeat, still pressed
      ++stats_.events;
      return;
    }
  }
  ++stats_.unmapped;
}

void EvdevTransport::Emit(const robot::RobotModel&, robot::RobotData& data) noexcept {
  const std::uint32_t stream = spec_.stream;
  if (!present()) {
    if (!lost_sample_due_) return;
    lost_sample_due_ = false;
    std::fill(out_.begin(), out_.end(), 0.0);
  } else {
    for (std::size_t i = 0; i < spec_.axes.size(); ++i) {
      const robot::EvdevAxisSpec& a = spec_.axes[i];
      double& out = out_[a.field - first_field_];
      const double raw = axis_value_[i];
      const double target = robot::ShapeAxis(a.shape, raw);
      if (std::isnan(target)) {
        out = target;  // not a value the device can give: the sample check names the field
        ++stats_.out_of_range;
        last_out_of_range_ = axis_value_[i];
        last_out_of_range_code_ = a.code;
        continue;
      }
      if (a.rate_per_s > 0 && std::isfinite(out)) {
        const double step = a.rate_per_s * tick_s_;
        out += std::clamp(target - out, -step, step);
      } else {
        out = target;
      }
    }
    for (std::size_t i = 0; i < spec_.buttons.size(); ++i)
      out_[spec_.buttons[i].field - first_field_] = button_value_[i] != 0 ? 1.0 : 0.0;
  }
  std::copy(out_.begin(), out_.end(), data.fields.begin() + first_field_);
  data.fresh[stream] = 1;
}

void EvdevTransport::Read(const robot::RobotModel& model, robot::RobotData& data) noexcept {
  if (!started_) {
    started_ = true;
    start_tick_ = data.tick;
  }
  if (is_file_) {
    if (file_open_) {
      const double elapsed_us = static_cast<double>(data.tick - start_tick_) * tick_s_ * 1e6;
      const EventRecord& first = file_.front();
      while (file_at_ < file_.size()) {
        const EventRecord& e = file_[file_at_];
        const double t_us = static_cast<double>(e.sec - first.sec) * 1e6 + static_cast<double>(e.usec - first.usec);
        if (t_us > elapsed_us + 0.5) break;
        Apply(e);
        ++file_at_;
      }
      if (file_at_ == file_.size()) {
        // The file's end: the device goes away a tick after its last event.
        const EventRecord& last = file_.back();
        const double t_us =
            static_cast<double>(last.sec - first.sec) * 1e6 + static_cast<double>(last.usec - first.usec);
        if (elapsed_us > t_us + 0.5) Lose();
      }
    }
  } else {
    if (fd_ < 0 && data.tick >= next_open_tick_) TryOpen(data.tick);
    while (fd_ >= 0) {
      const ssize_t n = ::read(fd_, buf_.data(), sizeof buf_);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
      if (n <= 0) {  // ENODEV: unplugged; 0: the end
        Lose();
        next_open_tick_ = data.tick + reopen_ticks_;
        break;
      }
      const auto count = static_cast<std::size_t>(n) / sizeof(EventRecord);
      for (std::size_t i = 0; i < count; ++i) Apply(buf_[i]);
      if (static_cast<std::size_t>(n) < sizeof buf_) break;
    }
  }
  Emit(model, data);
}

std::string EvdevTransport::Summary() const {
  const auto n = [](std::uint64_t v) { return std::to_string(v); };
  std::string s = "evdev " + spec_.device + ": " + n(stats_.events) + " events in " + n(stats_.reports) + " reports, " +
                  n(stats_.unmapped) + " unmapped, " + n(stats_.dropped) + " dropped reports, found " +
                  n(stats_.opens) + " times, lost " + n(stats_.losses) + " times, " + n(stats_.refused) + " refused";
  if (refusal_[0] != '\0') s += " (the last: " + std::string(refusal_) + ")";
  s += ", " + n(stats_.out_of_range) + " axis values outside their range";
  if (stats_.out_of_range > 0)
    s += " (the last: axis " + std::string(robot::InputCodeName(robot::InputCodeKind::kAxis, last_out_of_range_code_)) +
         " gave " + std::to_string(last_out_of_range_) + ")";
  return s;
}

}  // namespace pbppo::evdev
