#include "runtime/transport/can/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>

#include "runtime/core/clock.hpp"

namespace pbppo::can {
namespace {

constexpr std::size_t kCtrlBytes = CMSG_SPACE(sizeof(std::uint32_t)) + CMSG_SPACE(sizeof(struct timespec));

std::string Errno(const char* call, const std::string& iface, int e) {
  std::string m = "can bus '" + iface + "': " + call + ": " + std::strerror(e);
  if (e == EAFNOSUPPORT)
    m += " (this kernel has no SocketCAN; run the vcan tests inside tests/vm/vcan-vm, see docs/can.md)";
  if (e == ENODEV) m += " (no such interface; create it with 'ip link add dev " + iface + " type vcan')";
  return m;
}

void ToKernel(const CanFrame& f, struct canfd_frame* k) noexcept {
  std::memset(k, 0, sizeof *k);
  canid_t id = f.id;
  if ((f.flags & kFlagExtended) != 0) {
    id = (id & CAN_EFF_MASK) | CAN_EFF_FLAG;
  } else {
    id &= CAN_SFF_MASK;
  }
  if ((f.flags & kFlagRtr) != 0) id |= CAN_RTR_FLAG;
  if ((f.flags & kFlagError) != 0) id = (f.id & CAN_ERR_MASK) | CAN_ERR_FLAG;
  k->can_id = id;
  k->len = f.len;
  if ((f.flags & kFlagFd) != 0) {
    if ((f.flags & kFlagBrs) != 0) k->flags |= CANFD_BRS;
    if ((f.flags & kFlagEsi) != 0) k->flags |= CANFD_ESI;
  }
  std::memcpy(k->data, f.data, f.len);
}

void FromKernel(const struct canfd_frame& k, bool fd, CanFrame* f) noexcept {
  f->flags = 0;
  if ((k.can_id & CAN_ERR_FLAG) != 0) {
    f->id = k.can_id & CAN_ERR_MASK;
    f->flags |= kFlagError;
  } else if ((k.can_id & CAN_EFF_FLAG) != 0) {
    f->id = k.can_id & CAN_EFF_MASK;
    f->flags |= kFlagExtended;
  } else {
    f->id = k.can_id & CAN_SFF_MASK;
  }
  if ((k.can_id & CAN_RTR_FLAG) != 0) f->flags |= kFlagRtr;
  const std::uint8_t max = fd ? kFdMaxLen : kClassicMaxLen;
  f->len = std::min<std::uint8_t>(k.len, max);
  if (fd) {
    f->flags |= kFlagFd;
    if ((k.flags & CANFD_BRS) != 0) f->flags |= kFlagBrs;
    if ((k.flags & CANFD_ESI) != 0) f->flags |= kFlagEsi;
  }
  std::memcpy(f->data, k.data, f->len);
}

}  // namespace

struct SocketCanBus::Buffers {
  std::unique_ptr<struct canfd_frame[]> rx_frames, tx_frames;
  std::unique_ptr<struct iovec[]> rx_iov, tx_iov;
  std::unique_ptr<struct mmsghdr[]> rx_msgs, tx_msgs;
  std::unique_ptr<unsigned char[]> rx_ctrl;
  std::unique_ptr<std::size_t[]> tx_index;  // which input frame each batch slot holds
  std::uint32_t last_ovfl = 0;
};

Result<std::unique_ptr<SocketCanBus>> SocketCanBus::Open(const SocketCanOptions& o) {
  const std::string& iface = o.interface;
  if (iface.empty() || iface.size() >= IFNAMSIZ)
    return MakeError(ErrorCode::kInvalidValue, "can bus: interface name '" + iface + "' is empty or too long");
  if (o.rx_batch == 0 || o.tx_batch == 0 || o.rx_batch > 1024 || o.tx_batch > 1024)
    return MakeError(ErrorCode::kInvalidValue, "can bus '" + iface + "': rx_batch/tx_batch must be in 1..1024");
  for (std::uint32_t id : o.rx_ids) {
    if (id > CAN_SFF_MASK) {
      char b[16];
      std::snprintf(b, sizeof b, "0x%X", id);
      return MakeError(ErrorCode::kInvalidValue, "can bus '" + iface + "': rx_ids: " + b + " is not an 11-bit id");
    }
  }
  std::unique_ptr<SocketCanBus> bus(new SocketCanBus());
  bus->options_ = o;
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) return MakeError(ErrorCode::kUnsupported, Errno("socket(PF_CAN, SOCK_RAW, CAN_RAW)", iface, errno));
  bus->fd_ = fd;  // closed by the destructor from here on

  auto opt = [&](int level, int name, const void* v, socklen_t len, const char* what) -> Status {
    if (::setsockopt(fd, level, name, v, len) != 0)
      return MakeError(ErrorCode::kUnsupported, Errno(what, iface, errno));
    return {};
  };
  const int one = 1;
  if (o.fd) {
    if (auto st = opt(SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &one, sizeof one, "setsockopt(CAN_RAW_FD_FRAMES)"); !st)
      return st.error();
  }
  if (!o.receive_all) {
    std::vector<struct can_filter> filters;
    for (std::uint32_t id : o.rx_ids) filters.push_back({id, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG});
    if (auto st = opt(SOL_CAN_RAW, CAN_RAW_FILTER, filters.empty() ? nullptr : filters.data(),
                      static_cast<socklen_t>(filters.size() * sizeof(struct can_filter)), "setsockopt(CAN_RAW_FILTER)");
        !st)
      return st.error();
  }
  const can_err_mask_t err_mask = o.error_frames ? CAN_ERR_MASK : 0;
  if (auto st = opt(SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask, "setsockopt(CAN_RAW_ERR_FILTER)"); !st)
    return st.error();
  if (o.loopback_own) {
    if (auto st = opt(SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &one, sizeof one, "setsockopt(CAN_RAW_RECV_OWN_MSGS)"); !st)
      return st.error();
  }
  if (auto st = opt(SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one, "setsockopt(SO_RXQ_OVFL)"); !st) return st.error();
  if (auto st = opt(SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one, "setsockopt(SO_TIMESTAMPNS)"); !st) return st.error();
  if (o.rcvbuf_bytes > 0) {
    if (auto st = opt(SOL_SOCKET, SO_RCVBUF, &o.rcvbuf_bytes, sizeof(int), "setsockopt(SO_RCVBUF)"); !st)
      return st.error();
  }
  if (o.sndbuf_bytes > 0) {
    if (auto st = opt(SOL_SOCKET, SO_SNDBUF, &o.sndbuf_bytes, sizeof(int), "setsockopt(SO_SNDBUF)"); !st)
      return st.error();
  }
  const unsigned ifindex = ::if_nametoindex(iface.c_str());
  if (ifindex == 0) return MakeError(ErrorCode::kIo, Errno("if_nametoindex", iface, errno));
  struct sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(ifindex);
  if (::bind(fd, reinterpret_cast<const struct sockaddr*>(&addr), sizeof addr) != 0)
    return MakeError(ErrorCode::kIo, Errno("bind", iface, errno));

  auto b = std::make_unique<Buffers>();
  const std::size_t nr = o.rx_batch, nt = o.tx_batch;
  b->rx_frames = std::make_unique<struct canfd_frame[]>(nr);
  b->rx_iov = std::make_unique<struct iovec[]>(nr);
  b->rx_msgs = std::make_unique<struct mmsghdr[]>(nr);
  b->rx_ctrl = std::make_unique<unsigned char[]>(nr * kCtrlBytes);
  for (std::size_t i = 0; i < nr; ++i) {
    b->rx_iov[i] = {&b->rx_frames[i], sizeof(struct canfd_frame)};
    b->rx_msgs[i] = {};
    b->rx_msgs[i].msg_hdr.msg_iov = &b->rx_iov[i];
    b->rx_msgs[i].msg_hdr.msg_iovlen = 1;
  }
  b->tx_frames = std::make_unique<struct canfd_frame[]>(nt);
  b->tx_iov = std::make_unique<struct iovec[]>(nt);
  b->tx_msgs = std::make_unique<struct mmsghdr[]>(nt);
  b->tx_index = std::make_unique<std::size_t[]>(nt);
  for (std::size_t i = 0; i < nt; ++i) {
    b->tx_iov[i] = {&b->tx_frames[i], CAN_MTU};
    b->tx_msgs[i] = {};
    b->tx_msgs[i].msg_hdr.msg_iov = &b->tx_iov[i];
    b->tx_msgs[i].msg_hdr.msg_iovlen = 1;
  }
  bus->buf_ = std::move(b);
  return bus;
}

SocketCanBus::~SocketCanBus() {
  if (fd_ >= 0) ::close(fd_);
}

std::size_t SocketCanBus::ReceiveAtLeast(std::span<CanFrame> out, std::size_t want, std::int64_t timeout_ns) noexcept {
  std::size_t got = Receive(out);
  if (got >= want || got >= out.size()) return got;
  const std::int64_t t0 = MonotonicNs();
  while (got < want && got < out.size()) {
    const std::int64_t elapsed = MonotonicNs() - t0;
    if (elapsed >= timeout_ns) break;
    pollfd p{fd_, POLLIN, 0};
    const std::int64_t left_ms = (timeout_ns - elapsed + 999999) / 1000000;
    (void)poll(&p, 1, static_cast<int>(left_ms > 1000 ? 1000 : left_ms));
    got += Receive(out.subspan(got));
  }
  return got;
}

std::size_t SocketCanBus::Receive(std::span<CanFrame> out) noexcept {
  if (out.empty()) return 0;
  Buffers& b = *buf_;
  std::size_t n = 0;
  while (n < out.size()) {
    const auto want = static_cast<unsigned>(std::min<std::size_t>(options_.rx_batch, out.size() - n));
    for (unsigned i = 0; i < want; ++i) {
      struct msghdr& h = b.rx_msgs[i].msg_hdr;
      h.msg_control = &b.rx_ctrl[i * kCtrlBytes];
      h.msg_controllen = kCtrlBytes;
      h.msg_flags = 0;
    }
    const int r = ::recvmmsg(fd_, b.rx_msgs.get(), want, MSG_DONTWAIT, nullptr);
    if (r < 0) {
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) {
        ++stats_.rx_errors;
        stats_.last_errno = errno;
      }
      return n;
    }
    for (std::size_t i = 0; i < static_cast<std::size_t>(r); ++i) {
      struct msghdr& h = b.rx_msgs[i].msg_hdr;
      std::uint64_t t_ns = 0;
      for (struct cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr; c = CMSG_NXTHDR(&h, c)) {
        if (c->cmsg_level != SOL_SOCKET) continue;
        if (c->cmsg_type == SO_RXQ_OVFL) {
          std::uint32_t ovfl = 0;
          std::memcpy(&ovfl, CMSG_DATA(c), sizeof ovfl);
          stats_.rx_dropped_kernel += static_cast<std::uint32_t>(ovfl - b.last_ovfl);
          b.last_ovfl = ovfl;
        } else if (c->cmsg_type == SO_TIMESTAMPNS) {
          struct timespec ts{};
          std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
          t_ns = static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<std::uint64_t>(ts.tv_nsec);
        }
      }
      const unsigned len = b.rx_msgs[i].msg_len;
      if (len != CAN_MTU && len != CANFD_MTU) {
        ++stats_.rx_bad_size;
        continue;
      }
      const struct canfd_frame& k = b.rx_frames[i];
      if ((k.can_id & CAN_ERR_FLAG) != 0) {
        DecodeErrorFrame(k.can_id, k.data, stats_);
        if (!keep_error_frames) continue;
      } else {
        ++stats_.rx_frames;
      }
      CanFrame& f = out[n++];
      FromKernel(k, len == CANFD_MTU, &f);
      f.timestamp_ns = t_ns;
    }
    if (static_cast<unsigned>(r) < want) return n;  // the queue is empty: the next read is EAGAIN
  }
  ++stats_.rx_buffer_full;
  return n;
}

std::size_t SocketCanBus::Send(std::span<const CanFrame> frames) noexcept {
  Buffers& b = *buf_;
  std::size_t next = 0, accepted = 0;
  while (next < frames.size()) {
    // Fill a batch, leaving out frames this socket cannot carry.
    unsigned k = 0;
    while (k < options_.tx_batch && next < frames.size()) {
      const CanFrame& f = frames[next];
      const bool fd = (f.flags & kFlagFd) != 0;
      const bool ok = fd ? (options_.fd && IsValidFdLength(f.len)) : f.len <= kClassicMaxLen;
      if (!ok) {
        ++stats_.tx_errors;
        stats_.last_errno = EINVAL;
        ++next;
        continue;
      }
      ToKernel(f, &b.tx_frames[k]);
      b.tx_iov[k].iov_len = fd ? CANFD_MTU : CAN_MTU;
      b.tx_index[k] = next;
      ++k;
      ++next;
    }
    unsigned done = 0;
    while (done < k) {
      const int r = ::sendmmsg(fd_, b.tx_msgs.get() + done, k - done, MSG_DONTWAIT);
      if (r < 0) {
        if (errno == EINTR) continue;
        stats_.last_errno = errno;
        if (errno == ENOBUFS || errno == EAGAIN || errno == EWOULDBLOCK) {
          // The device queue is full: drop the rest of this tick's frames (never block, never retry).
          stats_.tx_dropped += (k - done) + (frames.size() - next);
        } else {
          // The failing message is dropped; the rest of the batch is tried again.
          ++stats_.tx_errors;
          ++done;
          continue;
        }
        return accepted;
      }
      for (int i = 0; i < r; ++i) {
        const unsigned j = done + static_cast<unsigned>(i);
        if (b.tx_msgs[j].msg_len != b.tx_iov[j].iov_len) {
          ++stats_.tx_short_writes;
        } else {
          ++stats_.tx_frames;
          ++accepted;
        }
      }
      done += static_cast<unsigned>(r);
    }
  }
  return accepted;
}

void DecodeErrorFrame(std::uint32_t can_id, const std::uint8_t data[8], BusStats& s) noexcept {
  ++s.error_frames;
  const std::uint32_t cls = can_id & CAN_ERR_MASK;
  if ((cls & CAN_ERR_TX_TIMEOUT) != 0) ++s.tx_timeouts;
  if ((cls & CAN_ERR_LOSTARB) != 0) ++s.lost_arbitration;
  if ((cls & CAN_ERR_CRTL) != 0) {
    const std::uint8_t c = data[1];
    if ((c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0) ++s.error_passive;
    if ((c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0) ++s.error_warning;
    if ((c & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) != 0 || c == CAN_ERR_CRTL_UNSPEC)
      ++s.controller_problems;
  }
  if ((cls & CAN_ERR_PROT) != 0) ++s.protocol_violations;
  if ((cls & CAN_ERR_ACK) != 0) ++s.no_ack;
  if ((cls & CAN_ERR_BUSOFF) != 0) {
    ++s.bus_off;
    s.is_bus_off = true;
  }
  if ((cls & CAN_ERR_RESTARTED) != 0) {
    ++s.restarted;
    s.is_bus_off = false;
  }
  if ((cls & CAN_ERR_CNT) != 0) {
    s.tx_error_count = data[6];
    s.rx_error_count = data[7];
  }
}

void DescribeErrorFrame(std::uint32_t can_id, const std::uint8_t data[8], char* out, std::size_t size) noexcept {
  if (size == 0) return;
  out[0] = '\0';
  std::size_t used = 0;
  auto add = [&](const char* s) {
    const int w = std::snprintf(out + used, size - used, "%s%s", used == 0 ? "" : ", ", s);
    if (w > 0) used = std::min(size - 1, used + static_cast<std::size_t>(w));
  };
  struct Bit {
    std::uint32_t mask;
    const char* text;  // null: the controller's problems, in data[1]
  };
  static constexpr Bit kClasses[] = {{CAN_ERR_TX_TIMEOUT, "tx timeout"},
                                     {CAN_ERR_LOSTARB, "lost arbitration"},
                                     {CAN_ERR_CRTL, nullptr},
                                     {CAN_ERR_PROT, "protocol violation"},
                                     {CAN_ERR_TRX, "transceiver"},
                                     {CAN_ERR_ACK, "no ack"},
                                     {CAN_ERR_BUSOFF, "bus-off"},
                                     {CAN_ERR_BUSERROR, "bus error"},
                                     {CAN_ERR_RESTARTED, "controller restarted"}};
  static constexpr Bit kController[] = {{CAN_ERR_CRTL_RX_OVERFLOW, "controller: rx overflow"},
                                        {CAN_ERR_CRTL_TX_OVERFLOW, "controller: tx overflow"},
                                        {CAN_ERR_CRTL_RX_WARNING, "controller: rx error-warning"},
                                        {CAN_ERR_CRTL_TX_WARNING, "controller: tx error-warning"},
                                        {CAN_ERR_CRTL_RX_PASSIVE, "controller: rx error-passive"},
                                        {CAN_ERR_CRTL_TX_PASSIVE, "controller: tx error-passive"},
                                        {CAN_ERR_CRTL_ACTIVE, "controller: back to error-active"}};
  const std::uint32_t cls = can_id & CAN_ERR_MASK;
  for (const Bit& b : kClasses) {
    if ((cls & b.mask) == 0) continue;
    if (b.text != nullptr) {
      add(b.text);
      continue;
    }
    const std::uint8_t c = data[1];
    for (const Bit& cb : kController)
      if ((c & cb.mask) != 0) add(cb.text);
    if (c == CAN_ERR_CRTL_UNSPEC) add("controller: unspecified problem");
  }
  if (used == 0) add("error frame without class");
}

}  // namespace pbppo::can
