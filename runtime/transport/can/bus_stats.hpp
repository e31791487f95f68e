// Per-bus counters of the CAN path, kept in the data and read by the safety supervisor and the
// profiler. Plain counters, no OS header; the SocketCAN transport and the frame dispatcher fill them.
#pragma once

#include <cstdint>

namespace pbppo::can {

struct BusStats {
  // Transport (socketcan.cpp)
  std::uint64_t rx_frames = 0;          // data frames received (error frames not included)
  std::uint64_t tx_frames = 0;          // frames the kernel accepted
  std::uint64_t tx_dropped = 0;         // frames not sent: ENOBUFS / EAGAIN (queue full), never retried
  std::uint64_t tx_short_writes = 0;    // a message written with fewer bytes than the frame
  std::uint64_t tx_errors = 0;          // any other send error (errno kept in last_errno)
  std::uint64_t rx_dropped_kernel = 0;  // frames dropped on a full socket queue (SO_RXQ_OVFL, seen with the next frame)
  std::uint64_t rx_buffer_full = 0;     // drains that stopped because the tick's buffer was full
  std::uint64_t rx_bad_size = 0;        // reads that were neither CAN_MTU nor CANFD_MTU
  std::uint64_t rx_errors = 0;          // read errors other than EAGAIN
  std::uint64_t error_frames = 0;       // error frames received (all classes)
  std::uint64_t bus_off = 0;            // error frames reporting bus-off
  std::uint64_t error_passive = 0;      // controller reports rx or tx error-passive
  std::uint64_t error_warning = 0;      // controller reports rx or tx error-warning
  std::uint64_t controller_problems = 0;  // other controller problems (overflows, ...)
  std::uint64_t protocol_violations = 0;  // CAN_ERR_PROT
  std::uint64_t no_ack = 0;               // CAN_ERR_ACK
  std::uint64_t tx_timeouts = 0;          // CAN_ERR_TX_TIMEOUT
  std::uint64_t lost_arbitration = 0;     // CAN_ERR_LOSTARB
  std::uint64_t restarted = 0;            // CAN_ERR_RESTARTED
  std::uint8_t tx_error_count = 0;        // last reported TEC (CAN_ERR_CNT)
  std::uint8_t rx_error_count = 0;        // last reported REC
  bool is_bus_off = false;                // latched by bus-off, cleared by a "restarted" frame
  int last_errno = 0;
  // Dispatch (can_table.cpp)
  std::uint64_t decoded = 0;         // frames decoded into the data
  std::uint64_t unknown_ids = 0;     // identifiers not in the table (ignored)
  std::uint64_t wrong_lengths = 0;   // known identifier, wrong payload length (ignored)
  std::uint64_t wrong_motor_id = 0;  // MIT reply whose motor id byte is not the expected motor
};

}  // namespace pbppo::can
