#include "runtime/loop/log.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include "runtime/core/crc32.hpp"
#include "runtime/core/write_all.hpp"

namespace pbppo::loop {
namespace {

constexpr char kMagic[8] = {'P', 'B', 'P', 'P', 'O', 'L', 'O', 'G'};
// kChunk: a piece of a snapshot between the tick and the writer, never in a file.
enum RecordType : std::uint8_t { kInputs = 1, kOutputs = 2, kEnd = 3, kSnapshot = 4, kChunk = 5 };
constexpr std::size_t kChunkHead = 16;     // u32 snapshot bytes, u32 offset, u64 records dropped before it
constexpr std::size_t kMaxNextName = 255;  // the end record's next file name (a file name's limit)

const char* TypeName(std::uint8_t t) {
  return t == kInputs     ? "inputs"
         : t == kOutputs  ? "outputs"
         : t == kEnd      ? "end"
         : t == kSnapshot ? "snapshot"
                          : "unknown";
}

// Appends little-endian values to a fixed buffer (sized for the largest record at Open).
struct Out {
  std::uint8_t* p;
  template <typename T>
  void Put(T v) noexcept {
    std::memcpy(p, &v, sizeof v);  // the supported hosts are little-endian (x86-64, aarch64)
    p += sizeof v;
  }
};

std::vector<std::uint8_t> Frame(std::uint8_t type, const std::uint8_t* payload, std::size_t n) {
  std::vector<std::uint8_t> r;
  r.reserve(n + 9);
  const auto len = static_cast<std::uint32_t>(n);
  const auto append = [&r](const void* p, std::size_t k) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    r.insert(r.end(), b, b + k);
  };
  r.push_back(type);
  append(&len, 4);
  append(payload, n);
  const std::uint32_t crc = Crc32(r.data(), r.size());
  append(&crc, 4);
  return r;
}

// The header: magic, version, payload and its CRC.
std::vector<std::uint8_t> HeaderBytes(const LogHeader& h) {
  std::vector<std::uint8_t> p;
  auto put = [&p](const auto v) {
    const auto* b = reinterpret_cast<const std::uint8_t*>(&v);
    p.insert(p.end(), b, b + sizeof v);
  };
  put(h.robot_hash);
  put(h.source_hash);
  put(h.tick_period_s);
  put(static_cast<std::uint32_t>(h.source));
  for (std::uint32_t v : {h.options, h.fields, h.streams, h.links, h.commands, h.motors}) put(v);
  put(static_cast<std::uint16_t>(h.robot.size()));
  p.insert(p.end(), h.robot.begin(), h.robot.end());
  put(h.sequence);
  put(h.run);
  const auto n = static_cast<std::uint32_t>(p.size());
  const std::uint32_t crc = Crc32(p.data(), p.size());
  std::vector<std::uint8_t> head;
  head.reserve(16 + p.size() + 4);
  const auto append = [&head](const void* v, std::size_t k) {
    const auto* b = static_cast<const std::uint8_t*>(v);
    head.insert(head.end(), b, b + k);
  };
  append(kMagic, 8);
  append(&kLogVersion, 4);
  append(&n, 4);
  append(p.data(), p.size());
  append(&crc, 4);
  return head;
}

std::string BaseName(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

std::string RotatedPath(const std::string& path, std::uint32_t sequence) {
  if (sequence == 0) return path;
  const std::size_t slash = path.rfind('/');
  const std::size_t name = slash == std::string::npos ? 0 : slash + 1;
  std::size_t dot = path.rfind('.');
  if (dot == std::string::npos || dot <= name) dot = path.size();  // no extension (a leading dot is none)
  return path.substr(0, dot) + "." + std::to_string(sequence) + path.substr(dot);
}

std::uint64_t LogHash(std::span<const std::uint8_t> bytes) noexcept {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (std::uint8_t b : bytes) {
    h ^= b;
    h *= 0x100000001b3ull;
  }
  return h;
}

LogHeader MakeLogHeader(const robot::RobotModel& m, SourceKind source, std::uint64_t source_hash,
                        const LoopOptions& options) {
  LogHeader h;
  h.robot_hash = m.hash;
  h.source_hash = source_hash;
  h.tick_period_s = m.tick_period_s;
  h.source = source;
  h.options = (options.shutdown_after_source ? 1u : 0u) | (options.stop_at_end_field ? 2u : 0u);
  h.fields = static_cast<std::uint32_t>(m.fields.size());
  h.streams = static_cast<std::uint32_t>(m.streams.size());
  h.links = static_cast<std::uint32_t>(m.supervisor_model.transport_names.size());
  h.commands = static_cast<std::uint32_t>(m.commands.size());
  h.motors = static_cast<std::uint32_t>(m.motors.size());
  h.robot = m.name;
  return h;
}

// Fixed-size slots between the tick (one producer) and the writer thread (one consumer).
struct Recorder::Ring {
  std::size_t slot_bytes = 0, capacity = 0;
  std::vector<std::uint8_t> bytes;
  std::vector<std::uint32_t> sizes;
  alignas(64) std::atomic<std::size_t> head{0};
  alignas(64) std::atomic<std::size_t> tail{0};
};

Result<std::unique_ptr<Recorder>> Recorder::Open(const std::string& path, const robot::RobotModel& m,
                                                 const LogHeader& h, const RecordOptions& options) {
  std::unique_ptr<Recorder> r(new Recorder());
  r->path_ = path;
  r->options_ = options;
  r->header_ = h;
  r->header_.sequence = 0;
  // The recording: the same in every file of it (its start, in ns since the epoch, and the process).
  r->header_.run = static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count()) ^
                   (static_cast<std::uint64_t>(::getpid()) << 48);
  const std::size_t inputs = 8 + 4 + 1 + 4 + 8 * m.streams.size() + 8 * m.fields.size() + 4 + 5 * h.links;
  const std::size_t outputs = 8 + 2 + 8 * m.commands.size() + m.motors.size();
  r->scratch_.assign(std::max({inputs, outputs, kChunkHead + 240}), 0);
  r->tick_bytes_ = (inputs + 9) + 2 * (outputs + 9);  // a tick's records (and a shutdown's last output)
  r->ring_ = std::make_unique<Ring>();
  r->ring_->slot_bytes = r->scratch_.size() + 9;
  r->ring_->capacity = std::max<std::size_t>(options.queue_records, 2);
  r->ring_->bytes.assign(r->ring_->slot_bytes * r->ring_->capacity, 0);
  r->ring_->sizes.assign(r->ring_->capacity, 0);
  r->batch_.assign(std::max<std::size_t>(std::size_t{64} << 10, r->ring_->slot_bytes), 0);
  r->batch_sizes_.assign(r->batch_.size() / 9 + 1, 0);
  // A file size limit (ulimit -f, LimitFSIZE=) would stop the process with SIGXFSZ at the write
  // past it: ignored, the write fails (EFBIG) and the recorder stops recording instead.
  std::signal(SIGXFSZ, SIG_IGN);
  r->fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (r->fd_ < 0) return MakeError(ErrorCode::kIo, "log " + path + ": cannot write: " + std::strerror(errno));
  const std::vector<std::uint8_t> head = HeaderBytes(r->header_);
  int error = 0;
  if (WriteAll(r->fd_, head.data(), head.size(), &error) != head.size()) {
    ::close(r->fd_);
    r->fd_ = -1;
    ::unlink(path.c_str());
    return MakeError(ErrorCode::kIo, "log " + path + ": cannot write the header: " + std::strerror(error));
  }
  r->file_bytes_ = head.size();
  for (std::uint64_t& b : r->boundary_) b = head.size();
  r->kept_.push_back(path);
  Recorder* self = r.get();
  r->thread_ = std::thread([self] { self->Run(); });
  return r;
}

Status AttachRecorder(const robot::RobotModel& m, const robot::RobotData& d, LoopData& loop, Recorder* r) {
  loop.recorder = r;
  if (r == nullptr) return {};
  StateWriter count;
  SaveState(m, d, loop, count);
  r->snapshot_.assign(count.size(), 0);
  r->assembled_.assign(count.size(), 0);
  if (r->options_.max_file_bytes == 0) return {};
  // A file holds its header, the snapshot record, its end record (naming the next file) and at
  // least four ticks.
  const std::uint64_t fixed = HeaderBytes(r->header_).size() + 9 + count.size() + 9 + 23 + 2 + kMaxNextName;
  const std::uint64_t least = fixed + 4 * r->tick_bytes_;
  if (r->options_.max_file_bytes < least) {
    loop.recorder = nullptr;
    return MakeError(ErrorCode::kInvalidValue,
                     "log " + r->path_ + ": a file of at most " + std::to_string(r->options_.max_file_bytes) +
                         " bytes cannot hold a header, a snapshot of the loop (" + std::to_string(count.size()) +
                         " bytes), an end record and four ticks (" + std::to_string(r->tick_bytes_) +
                         " bytes each): it needs at least " + std::to_string(least) + " bytes");
  }
  r->budget_ = r->options_.max_file_bytes - fixed;
  return {};
}

Recorder::~Recorder() {
  (void)Stop();
}

bool Recorder::Push(std::uint8_t type, const std::uint8_t* payload, std::size_t n) noexcept {
  Ring& q = *ring_;
  const std::size_t head = q.head.load(std::memory_order_relaxed);
  if (head - q.tail.load(std::memory_order_acquire) >= q.capacity || n + 9 > q.slot_bytes) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  std::uint8_t* s = &q.bytes[(head % q.capacity) * q.slot_bytes];
  s[0] = type;
  const auto len = static_cast<std::uint32_t>(n);
  std::memcpy(s + 1, &len, 4);
  std::memcpy(s + 5, payload, n);
  const std::uint32_t crc = Crc32(s, 5 + n);
  std::memcpy(s + 5 + n, &crc, 4);
  q.sizes[head % q.capacity] = static_cast<std::uint32_t>(n + 9);
  q.head.store(head + 1, std::memory_order_release);
  if (type != kChunk) queued_bytes_ += n + 9;
  return true;
}

bool Recorder::snapshot_due() const noexcept {
  return budget_ > 0 && queued_bytes_ + tick_bytes_ > budget_ && !failed_.load(std::memory_order_relaxed);
}

void Recorder::Snapshot(const robot::RobotModel& m, const robot::RobotData& d, const LoopData& loop) noexcept {
  Ring& q = *ring_;
  const std::size_t piece = q.slot_bytes - 9 - kChunkHead;
  const std::size_t chunks = (snapshot_.size() + piece - 1) / piece;
  // Every chunk or none: the writer puts them together in order.
  if (q.capacity - (q.head.load(std::memory_order_relaxed) - q.tail.load(std::memory_order_acquire)) < chunks) return;
  StateWriter w(snapshot_.data(), snapshot_.size());
  SaveState(m, d, loop, w);
  if (w.overflow() || w.size() != snapshot_.size()) return;  // the state's size is fixed at set-up
  const std::uint64_t dropped = dropped_.load(std::memory_order_relaxed);
  for (std::size_t at = 0; at < snapshot_.size(); at += piece) {
    const std::size_t n = std::min(piece, snapshot_.size() - at);
    Out o{scratch_.data()};
    o.Put(static_cast<std::uint32_t>(snapshot_.size()));
    o.Put(static_cast<std::uint32_t>(at));
    o.Put(dropped);
    std::memcpy(o.p, &snapshot_[at], n);
    (void)Push(kChunk, scratch_.data(), kChunkHead + n);  // room was checked
  }
  queued_bytes_ = 0;  // the records from here on go to the next file
}

void Recorder::Inputs(const robot::RobotModel& m, const robot::RobotData& d, const rt::TickTiming& t,
                      const TickEvents& e) noexcept {
  Out o{scratch_.data()};
  o.Put(d.tick);
  o.Put(t.consecutive_misses);
  o.Put(static_cast<std::uint8_t>((e.arm ? 1 : 0) | (e.disarm ? 2 : 0) | (e.stop ? 4 : 0) | (e.estop ? 8 : 0) |
                                  (t.missed ? 16 : 0) | (e.rearm ? 32 : 0)));
  std::uint8_t* count = o.p;
  o.Put(std::uint32_t{0});
  std::uint32_t fresh = 0;
  for (std::size_t s = 0; s < m.streams.size(); ++s) {
    if (d.fresh[s] == 0) continue;
    ++fresh;
    const robot::StreamSpec& spec = m.streams[s];
    o.Put(static_cast<std::uint32_t>(s));
    o.Put(spec.field_count);
    for (std::uint32_t f = 0; f < spec.field_count; ++f) o.Put(d.fields[spec.first_field + f]);
  }
  std::memcpy(count, &fresh, 4);
  count = o.p;
  o.Put(std::uint32_t{0});
  std::uint32_t news = 0;
  for (std::size_t k = 0; k < d.transports.size(); ++k) {
    const safety::TransportHealth& h = d.transports[k];
    const auto bits = static_cast<std::uint8_t>((h.degraded ? 1 : 0) | (h.fault ? 2 : 0) | (h.lost ? 4 : 0));
    if (bits == 0) continue;
    ++news;
    o.Put(static_cast<std::uint32_t>(k));
    o.Put(bits);
  }
  std::memcpy(count, &news, 4);
  (void)Push(kInputs, scratch_.data(), static_cast<std::size_t>(o.p - scratch_.data()));
}

void Recorder::Outputs(const robot::RobotModel&, const robot::RobotData& d, Phase phase) noexcept {
  Out o{scratch_.data()};
  o.Put(d.tick);
  o.Put(static_cast<std::uint8_t>(phase));
  o.Put(static_cast<std::uint8_t>(d.mode));
  for (double c : d.command) o.Put(c);
  for (robot::MotorCommand c : d.motors) o.Put(static_cast<std::uint8_t>(c));
  (void)Push(kOutputs, scratch_.data(), static_cast<std::size_t>(o.p - scratch_.data()));
}

// Moves what is queued into the file (or, once a write has failed, counts it as not written); a
// snapshot's chunks are put together and begin the next file.
void Recorder::Drain() {
  Ring& q = *ring_;
  std::size_t tail = q.tail.load(std::memory_order_relaxed);
  const std::size_t head = q.head.load(std::memory_order_acquire);
  while (tail != head) {
    std::size_t bytes = 0, n = 0;
    bool chunk = false;
    for (; tail != head && n < batch_sizes_.size(); ++tail, ++n) {
      const std::size_t slot = tail % q.capacity;
      if (q.bytes[slot * q.slot_bytes] == kChunk) {
        chunk = true;
        break;
      }
      if (bytes + q.sizes[slot] > batch_.size()) break;
      if (!failed_.load(std::memory_order_relaxed))
        std::memcpy(&batch_[bytes], &q.bytes[slot * q.slot_bytes], q.sizes[slot]);
      bytes += q.sizes[slot];
      batch_sizes_[n] = q.sizes[slot];
    }
    q.tail.store(tail, std::memory_order_release);  // the slots are free again
    if (failed_.load(std::memory_order_relaxed)) {
      not_written_.fetch_add(n, std::memory_order_relaxed);
    } else if (n > 0) {
      int error = 0;
      const std::size_t done = WriteAll(fd_, batch_.data(), bytes, &error);
      // The records written whole, each boundary remembered (to back off to if the end record
      // does not fit after a failure).
      std::size_t whole = 0, k = 0;
      for (; k < n && whole + batch_sizes_[k] <= done; ++k) {
        whole += batch_sizes_[k];
        ++file_records_;
        boundary_[file_records_ % kBoundaries] = file_bytes_ + whole;
        written_.fetch_add(1, std::memory_order_relaxed);
      }
      file_bytes_ += whole;
      if (error != 0) {
        not_written_.fetch_add(n - k, std::memory_order_relaxed);
        Fail(error, "write failed after " + std::to_string(written_.load(std::memory_order_relaxed)) +
                        " records: " + std::strerror(error));
      }
    }
    if (chunk) {
      TakeChunk(&q.bytes[(tail % q.capacity) * q.slot_bytes]);
      q.tail.store(++tail, std::memory_order_release);
    }
  }
}

void Recorder::TakeChunk(const std::uint8_t* slot) {
  std::uint32_t len = 0, total = 0, at = 0;
  std::uint64_t dropped = 0;
  std::memcpy(&len, slot + 1, 4);
  std::memcpy(&total, slot + 5, 4);
  std::memcpy(&at, slot + 9, 4);
  std::memcpy(&dropped, slot + 13, 8);
  const std::size_t n = len - kChunkHead;
  if (total != assembled_.size() || at + n > total) return;  // cannot happen: the tick sized them
  std::memcpy(&assembled_[at], slot + 5 + kChunkHead, n);
  if (at + n == total && !failed_.load(std::memory_order_relaxed)) Rotate(total, dropped);
}

// Ends the current file with an end record naming the next, and begins the next: its header and
// the snapshot. Where the next cannot be written, recording stops there as after a failed write
// (the current file ends naming the error).
void Recorder::Rotate(std::size_t snapshot_bytes, std::uint64_t dropped_before) {
  const std::uint32_t next = sequence_.load(std::memory_order_relaxed) + 1;
  const std::string next_path = RotatedPath(path_, next);
  // The oldest files beyond keep_files go first (room on a full disk).
  while (options_.keep_files > 0 && kept_.size() + 1 > options_.keep_files) {
    (void)::unlink(kept_.front().c_str());
    kept_.erase(kept_.begin());
    deleted_.fetch_add(1, std::memory_order_relaxed);
  }
  const std::string after = " after " + std::to_string(written_.load(std::memory_order_relaxed)) + " records";
  const int fd = ::open(next_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int e = errno;
    Fail(e, "cannot begin the next file " + next_path + after + ": " + std::strerror(e));
    return;
  }
  LogHeader h = header_;
  h.sequence = next;
  const std::vector<std::uint8_t> head = HeaderBytes(h);
  const std::vector<std::uint8_t> snap = Frame(kSnapshot, assembled_.data(), snapshot_bytes);
  int e = 0;
  if (WriteAll(fd, head.data(), head.size(), &e) == head.size()) (void)WriteAll(fd, snap.data(), snap.size(), &e);
  // The current file ends naming the next (its name only: the files lie side by side).
  if (e == 0) e = WriteEnd(LogEnd::kRotated, 0, dropped_before - file_dropped_from_, BaseName(next_path));
  if (e != 0) {
    ::close(fd);
    ::unlink(next_path.c_str());
    Fail(e, "cannot begin the next file " + next_path + after + ": " + std::strerror(e));
    return;
  }
  (void)::close(fd_);  // what it holds is written; a late error of the close names nothing to redo
  fd_ = fd;
  kept_.push_back(next_path);
  file_bytes_ = head.size() + snap.size();
  for (std::uint64_t& b : boundary_) b = file_bytes_;
  file_records_ = 0;
  file_dropped_from_ = dropped_before;
  ended_ = false;
  end_at_ = 0;
  sequence_.store(next, std::memory_order_relaxed);
}

// Stops recording on a failure: the file cut back to its last whole record, the end record naming
// the error, the failure published to the tick's side.
void Recorder::Fail(int error, const std::string& what) {
  if (failed_.load(std::memory_order_relaxed)) return;
  failure_ = what;
  error_ = error;
  if (error != ENOENT) (void)WriteEnd(LogEnd::kWriteFailed, error, FileDropped(), "");
  failed_.store(true, std::memory_order_release);
}

// Writes the end record after the last whole record; after a failure, where the disk takes no more,
// backs off one record at a time (at most kBoundaries - 1), those records counted as not written.
// Returns 0, or the error number of what failed.
std::uint64_t Recorder::FileDropped() const noexcept {
  return dropped_.load(std::memory_order_relaxed) - file_dropped_from_;
}

std::vector<std::uint8_t> Recorder::EndRecord(LogEnd why, int error, std::uint64_t dropped,
                                              const std::string& next) const {
  const std::size_t name = std::min(next.size(), kMaxNextName);
  std::uint8_t payload[23 + kMaxNextName];
  Out o{payload};
  o.Put(dropped);
  o.Put(static_cast<std::uint8_t>(why));
  o.Put(static_cast<std::uint32_t>(error));
  o.Put(not_written_.load(std::memory_order_relaxed));
  o.Put(static_cast<std::uint16_t>(name));
  std::memcpy(o.p, next.data(), name);
  return Frame(kEnd, payload, 23 + name);
}

int Recorder::WriteEnd(LogEnd why, int error, std::uint64_t dropped, const std::string& next) {
  for (std::size_t back = 0; back < kBoundaries; ++back) {
    const std::uint64_t records = file_records_;
    const auto end = EndRecord(why, error, dropped, next);
    const std::uint64_t at = boundary_[records % kBoundaries];
    int e = 0;
    // After a failure the file may end inside a record: cut back to the boundary first (a stop
    // writes at the end of what was written, so a pipe or a terminal takes a log too).
    const bool cut = why == LogEnd::kWriteFailed || at != file_bytes_;
    if (cut && (::ftruncate(fd_, static_cast<off_t>(at)) != 0 || ::lseek(fd_, static_cast<off_t>(at), SEEK_SET) < 0))
      e = errno;
    else if (WriteAll(fd_, end.data(), end.size(), &e) == end.size()) {
      file_bytes_ = at + end.size();
      end_at_ = at;
      ended_ = true;
      return 0;
    }
    if (why != LogEnd::kWriteFailed || records == 0 || back + 1 == kBoundaries) {
      if (cut) (void)::ftruncate(fd_, static_cast<off_t>(at));  // the whole records stay
      return e != 0 ? e : EIO;
    }
    file_records_ = records - 1;  // one record less, room for the end
    written_.fetch_sub(1, std::memory_order_relaxed);
    not_written_.fetch_add(1, std::memory_order_relaxed);
  }
  return EIO;
}

void Recorder::Run() {
  // Every second or so: is the file still there (a removed directory takes its files along, and
  // writes to them then succeed into nothing)?
  int polls = 0;
  for (;;) {
    const bool stopping = stop_.load(std::memory_order_acquire);
    Drain();
    if (stopping) return;
    if (++polls >= 500 && !failed_.load(std::memory_order_relaxed)) {
      polls = 0;
      struct stat st{};
      if (::fstat(fd_, &st) == 0 && st.st_nlink == 0)
        Fail(ENOENT,
             "the file was removed after " + std::to_string(written_.load(std::memory_order_relaxed)) + " records");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

Status Recorder::Stop() {
  // Until it is joined, the writer owns fd_ (a rotation replaces it): nothing of it is read before.
  if (thread_.joinable()) {
    stop_.store(true, std::memory_order_release);
    thread_.join();
  }
  if (fd_ < 0) return {};
  if (!failed_.load(std::memory_order_relaxed)) {
    struct stat st{};
    if (::fstat(fd_, &st) == 0 && st.st_nlink == 0)
      Fail(ENOENT,
           "the file was removed after " + std::to_string(written_.load(std::memory_order_relaxed)) + " records");
    else if (const int e = WriteEnd(LogEnd::kStopped, 0, FileDropped(), ""); e != 0)
      Fail(e, "write failed after " + std::to_string(written_.load(std::memory_order_relaxed)) +
                  " records (the end record): " + std::strerror(e));
  }
  // The end record written at the failure counted the records lost until then: it is written over
  // (in place: no new space) with the run's final counts. Where that fails, the first one stays.
  if (failed_.load(std::memory_order_relaxed) && ended_) {
    const auto end = EndRecord(LogEnd::kWriteFailed, error_, FileDropped(), "");
    (void)!::pwrite(fd_, end.data(), end.size(), static_cast<off_t>(end_at_));
  }
  const bool closed = ::close(fd_) == 0;
  fd_ = -1;
  if (failed_.load(std::memory_order_relaxed)) {
    const std::uint64_t lost = not_written_.load(std::memory_order_relaxed);
    const std::uint32_t seq = sequence_.load(std::memory_order_relaxed);
    const std::string file =
        seq == 0 ? "the file"
                 : "the last file, " + RotatedPath(path_, seq) + " (" + std::to_string(seq + 1) + " files),";
    return MakeError(ErrorCode::kIo, "log " + path_ + ": " + failure_ + "; " + std::to_string(lost) +
                                         " records not written; " + file + " holds " + std::to_string(file_records_) +
                                         " whole records" +
                                         (ended_ ? " and its end record" : ", without its end record"));
  }
  if (!closed) return MakeError(ErrorCode::kIo, "log " + path_ + ": closing the file failed: " + std::strerror(errno));
  return {};
}

// ---- reading -------------------------------------------------------------------------------------

namespace {

class Reader {
 public:
  Reader(std::span<const std::uint8_t> b, std::size_t base, std::string origin)
      : b_(b), base_(base), origin_(std::move(origin)) {}
  std::size_t offset() const noexcept { return base_ + at_; }
  std::size_t left() const noexcept { return b_.size() - at_; }
  Error Fail(std::size_t offset, const std::string& where, const std::string& what) const {
    return MakeError(ErrorCode::kFormat, origin_ + ": offset " + std::to_string(offset) + ": " + where + ": " + what);
  }
  // `n` more bytes for `field`, or the error naming it.
  Status Need(std::size_t n, const std::string& where, const char* field) const {
    if (left() >= n) return {};
    return Fail(offset(), where,
                std::string("field '") + field + "': truncated (needs " + std::to_string(n) + " bytes, " +
                    std::to_string(left()) + " left)");
  }
  template <typename T>
  Result<T> Get(const std::string& where, const char* field) {
    if (auto st = Need(sizeof(T), where, field); !st) return st.error();
    T v;
    std::memcpy(&v, b_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  // A count that must not exceed `max` (each element at least `each` bytes).
  Result<std::uint32_t> Count(const std::string& where, const char* field, std::uint32_t max, std::size_t each) {
    const std::size_t at = offset();
    auto n = Get<std::uint32_t>(where, field);
    if (!n) return n;
    if (*n > max)
      return Fail(at, where,
                  std::string("field '") + field + "': " + std::to_string(*n) + " is above " + std::to_string(max));
    if (auto st = Need(static_cast<std::size_t>(*n) * each, where, field); !st) return st.error();
    return n;
  }
  std::span<const std::uint8_t> Take(std::size_t n) noexcept {
    const auto s = b_.subspan(at_, n);
    at_ += n;
    return s;
  }

 private:
  std::span<const std::uint8_t> b_;
  std::size_t base_ = 0;
  std::string origin_;
  std::size_t at_ = 0;
};

#define PBPPO_GET(var, r, T, where, field)           \
  T var{};                                           \
  do {                                               \
    auto v_ = (r).template Get<T>((where), (field)); \
    if (!v_) return std::move(v_).error();           \
    var = *v_;                                       \
  } while (false)
#define PBPPO_COUNT(var, r, where, field, max, each)      \
  std::uint32_t var = 0;                                  \
  do {                                                    \
    auto v_ = (r).Count((where), (field), (max), (each)); \
    if (!v_) return std::move(v_).error();                \
    var = *v_;                                            \
  } while (false)

Status ParseHeader(Reader& r, std::uint32_t version, LogHeader& h) {
  const std::string w = "header";
  PBPPO_GET(robot_hash, r, std::uint64_t, w, "robot_hash");
  PBPPO_GET(source_hash, r, std::uint64_t, w, "source_hash");
  PBPPO_GET(period, r, double, w, "tick_period_s");
  const std::size_t kind_at = r.offset();
  PBPPO_GET(kind, r, std::uint32_t, w, "source");
  if (kind > 2) return r.Fail(kind_at, w, "field 'source': " + std::to_string(kind) + " is not 0, 1 or 2");
  h.robot_hash = robot_hash;
  h.source_hash = source_hash;
  h.tick_period_s = period;
  h.source = static_cast<SourceKind>(kind);
  std::uint32_t* counts[] = {&h.options, &h.fields, &h.streams, &h.links, &h.commands, &h.motors};
  const char* names[] = {"options", "fields", "streams", "links", "commands", "motors"};
  for (int i = 0; i < 6; ++i) {
    PBPPO_GET(v, r, std::uint32_t, w, names[i]);
    if (i == 0 && v > 3)
      return r.Fail(r.offset() - 4, w, "field 'options': " + std::to_string(v) + " has bits other than 1 and 2");
    if (i > 0 && v > 65536)
      return r.Fail(r.offset() - 4, w,
                    std::string("field '") + names[i] + "': " + std::to_string(v) + " is above 65536");
    *counts[i] = v;
  }
  PBPPO_GET(len, r, std::uint16_t, w, "robot");
  if (auto st = r.Need(len, w, "robot"); !st) return st;
  const auto name = r.Take(len);
  h.robot.assign(name.begin(), name.end());
  if (version >= 3) {
    PBPPO_GET(sequence, r, std::uint32_t, w, "sequence");
    PBPPO_GET(run, r, std::uint64_t, w, "run");
    h.sequence = sequence;
    h.run = run;
  }
  if (!(std::isfinite(h.tick_period_s) && h.tick_period_s > 0))
    return r.Fail(r.offset(), w, "field 'tick_period_s': " + std::to_string(h.tick_period_s) + " is not a period");
  return {};
}

Status ParseRecord(Reader& r, const LogHeader& h, const std::string& w, LogRecord& rec, Log& log) {
  if (rec.type == kInputs) {
    LogInputs& in = rec.inputs;
    PBPPO_GET(tick, r, std::uint64_t, w, "tick");
    PBPPO_GET(misses, r, std::uint32_t, w, "consecutive_misses");
    PBPPO_GET(flags, r, std::uint8_t, w, "flags");
    in.tick = tick;
    in.consecutive_misses = misses;
    in.flags = flags;
    PBPPO_COUNT(fresh, r, w, "streams", h.streams, 8);
    for (std::uint32_t k = 0; k < fresh; ++k) {
      const std::size_t at = r.offset();
      PBPPO_GET(stream, r, std::uint32_t, w, "stream");
      if (stream >= h.streams)
        return r.Fail(at, w,
                      "field 'stream': " + std::to_string(stream) + " is not below " + std::to_string(h.streams));
      PBPPO_COUNT(n, r, w, "values", h.fields, 8);
      in.streams.push_back(stream);
      for (std::uint32_t i = 0; i < n; ++i) {
        PBPPO_GET(v, r, double, w, "values");
        in.values.push_back(v);
      }
    }
    PBPPO_COUNT(links, r, w, "links", h.links, 5);
    for (std::uint32_t k = 0; k < links; ++k) {
      const std::size_t at = r.offset();
      PBPPO_GET(link, r, std::uint32_t, w, "link");
      PBPPO_GET(bits, r, std::uint8_t, w, "health");
      if (link >= h.links || bits > 7)
        return r.Fail(at, w, "field 'link': " + std::to_string(link) + " health " + std::to_string(bits));
      in.links.emplace_back(link, bits);
    }
  } else if (rec.type == kOutputs) {
    LogOutputs& out = rec.outputs;
    PBPPO_GET(tick, r, std::uint64_t, w, "tick");
    const std::size_t at = r.offset();
    PBPPO_GET(phase, r, std::uint8_t, w, "phase");
    PBPPO_GET(mode, r, std::uint8_t, w, "mode");
    if (phase >= kPhaseCount || mode > 3)
      return r.Fail(at, w, "field 'phase': " + std::to_string(phase) + ", mode " + std::to_string(mode));
    out.tick = tick;
    out.phase = phase;
    out.mode = mode;
    if (auto st = r.Need(8 * std::size_t{h.commands} + h.motors, w, "commands"); !st) return st;
    for (std::uint32_t k = 0; k < h.commands; ++k) out.commands.push_back(*r.Get<double>(w, "commands"));
    for (std::uint32_t k = 0; k < h.motors; ++k) {
      const std::uint8_t c = *r.Get<std::uint8_t>(w, "motors");
      if (c > 3) return r.Fail(r.offset() - 1, w, "field 'motors': " + std::to_string(c) + " is not a motor command");
      out.motors.push_back(c);
    }
  } else if (rec.type == kEnd) {
    PBPPO_GET(dropped, r, std::uint64_t, w, "dropped");
    log.dropped = dropped;
    if (log.version >= 2) {
      const std::size_t at = r.offset();
      PBPPO_GET(why, r, std::uint8_t, w, "why");
      PBPPO_GET(error, r, std::uint32_t, w, "error");
      PBPPO_GET(lost, r, std::uint64_t, w, "not_written");
      const auto last = log.version >= 3 ? LogEnd::kRotated : LogEnd::kWriteFailed;
      if (why > static_cast<std::uint8_t>(last))
        return r.Fail(at, w, "field 'why': " + std::to_string(why) + " is not a reason a log ends");
      log.end = static_cast<LogEnd>(why);
      log.end_error = error;
      log.not_written = lost;
    }
    if (log.version >= 3) {
      PBPPO_GET(len, r, std::uint16_t, w, "next");
      if (auto st = r.Need(len, w, "next"); !st) return st;
      const auto name = r.Take(len);
      log.next.assign(name.begin(), name.end());
      if ((log.end == LogEnd::kRotated) != !log.next.empty() || log.next.find('/') != std::string::npos)
        return r.Fail(r.offset() - len, w,
                      "field 'next': '" + log.next + "' (a rotated log names the next file, no other does)");
    }
    log.complete = true;
  } else if (rec.type == kSnapshot && log.version >= 3) {
    if (r.left() == 0) return r.Fail(r.offset(), w, "field 'state': empty");
    const auto state = r.Take(r.left());
    log.snapshot.assign(state.begin(), state.end());
  } else {
    return r.Fail(r.offset(), w, "field 'type': " + std::to_string(rec.type) + " is not a record type");
  }
  if (r.left() != 0) return r.Fail(r.offset(), w, std::to_string(r.left()) + " bytes after the last field");
  return {};
}

}  // namespace

Result<Log> ParseLog(std::span<const std::uint8_t> bytes, const std::string& origin, LogTail tail) {
  Log log;
  Reader r(bytes, 0, origin);
  if (auto st = r.Need(16, "header", "magic"); !st) return st.error();
  const auto magic = r.Take(8);
  if (std::memcmp(magic.data(), kMagic, 8) != 0)
    return r.Fail(0, "header", "field 'magic': not a pbppo log (PBPPOLOG)");
  PBPPO_GET(version, r, std::uint32_t, "header", "version");
  if (version < 1 || version > kLogVersion)
    return r.Fail(8, "header",
                  "field 'version': " + std::to_string(version) + " (this reader knows 1 to " +
                      std::to_string(kLogVersion) + ")");
  log.version = version;
  PBPPO_GET(n, r, std::uint32_t, "header", "length");
  if (auto st = r.Need(std::size_t{n} + 4, "header", "payload"); !st) return st.error();
  const std::size_t payload_at = r.offset();
  const auto payload = r.Take(n);
  const std::uint32_t crc = *r.Get<std::uint32_t>("header", "crc");
  if (Crc32(payload.data(), payload.size()) != crc)
    return r.Fail(payload_at + n, "header", "CRC does not match its payload");
  Reader hr(payload, payload_at, origin);
  if (auto st = ParseHeader(hr, version, log.header); !st) return st.error();
  if (hr.left() != 0) return hr.Fail(hr.offset(), "header", std::to_string(hr.left()) + " bytes after the last field");
  // A record the file ends inside: with kAcceptCut the log ends before it.
  const bool accept_cut = tail == LogTail::kAcceptCut;
  auto cut = [&](std::size_t at, const std::string& what, std::size_t needs) {
    log.cut_at = at;
    log.cut_reason = "the file ends inside " + what + ": it needs " + std::to_string(needs) + " bytes, " +
                     std::to_string(bytes.size() - at) + " are left";
  };
  for (std::size_t k = 0; r.left() > 0; ++k) {
    LogRecord rec;
    rec.offset = r.offset();
    if (log.complete) return r.Fail(rec.offset, "record " + std::to_string(k), "after the end record");
    if (accept_cut && r.left() < 5) {
      cut(rec.offset, "record " + std::to_string(k), 5);
      break;
    }
    PBPPO_GET(type, r, std::uint8_t, "record " + std::to_string(k), "type");
    rec.type = type;
    const std::string w = "record " + std::to_string(k) + " (" + TypeName(type) + ")";
    const std::size_t len_at = r.offset();
    PBPPO_GET(len, r, std::uint32_t, w, "length");
    if (len > (1u << 24)) return r.Fail(len_at, w, "field 'length': " + std::to_string(len) + " is above 16 MiB");
    if (accept_cut && r.left() < std::size_t{len} + 4) {
      cut(rec.offset, w, 5 + std::size_t{len} + 4);
      break;
    }
    if (auto st = r.Need(std::size_t{len} + 4, w, "payload"); !st) return st.error();
    const auto body = r.Take(len);
    const std::uint32_t stored = *r.Get<std::uint32_t>(w, "crc");
    if (Crc32(bytes.data() + rec.offset, 5 + std::size_t{len}) != stored)
      return r.Fail(rec.offset, w, "CRC does not match the record");
    Reader rr(body, rec.offset + 5, origin);
    if (type == kSnapshot && k != 0) return r.Fail(rec.offset, w, "a snapshot is only the first record");
    if (auto st = ParseRecord(rr, log.header, w, rec, log); !st) return st.error();
    if (type != kEnd && type != kSnapshot) log.records.push_back(std::move(rec));
  }
  if (!log.complete && !accept_cut) return r.Fail(bytes.size(), "end", "no end record: the log is truncated");
  if (!log.complete && log.cut_reason.empty()) {
    log.cut_at = bytes.size();
    log.cut_reason = log.records.empty() ? "no record and no end record after the header"
                                         : "no end record after record " +
                                               std::to_string(log.records.size() - (log.snapshot.empty() ? 1 : 0));
  }
  return log;
}

#undef PBPPO_COUNT
#undef PBPPO_GET

Result<Log> ReadLog(const std::string& path, LogTail tail) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return MakeError(ErrorCode::kIo, path + ": cannot open");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  return ParseLog(bytes, path, tail);
}

std::string DescribeEnd(const Log& log) {
  if (!log.complete) return log.cut_reason;
  if (log.end == LogEnd::kStopped) return "stopped";
  if (log.end == LogEnd::kRotated) return "rotated: the recording goes on in " + log.next;
  return "a write failed: " + std::string(std::strerror(static_cast<int>(log.end_error))) + " (" +
         std::to_string(log.end_error) + "); " + std::to_string(log.not_written) + " records not written after it";
}

}  // namespace pbppo::loop
