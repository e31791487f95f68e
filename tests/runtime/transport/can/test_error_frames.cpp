// Decoding of SocketCAN error frames (synthetic: vcan has no controller that could raise them).
#include <doctest/doctest.h>
#include <linux/can.h>
#include <linux/can/error.h>

#include <cstring>
#include <string>

#include "runtime/transport/can/socketcan.hpp"

using namespace pbppo::can;

TEST_CASE("bus-off - error-passive - warnings - controller problems and counters are decoded") {
  BusStats s;
  std::uint8_t d[8] = {};
  DecodeErrorFrame(CAN_ERR_FLAG | CAN_ERR_BUSOFF, d, s);
  CHECK(s.error_frames == 1);
  CHECK(s.bus_off == 1);
  CHECK(s.is_bus_off);
  d[1] = CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_WARNING;
  d[6] = 130;
  d[7] = 12;
  DecodeErrorFrame(CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_CNT, d, s);
  CHECK(s.error_passive == 1);
  CHECK(s.error_warning == 1);
  CHECK(s.controller_problems == 0);
  CHECK(s.tx_error_count == 130);
  CHECK(s.rx_error_count == 12);
  d[1] = CAN_ERR_CRTL_RX_OVERFLOW;
  DecodeErrorFrame(CAN_ERR_FLAG | CAN_ERR_CRTL, d, s);
  CHECK(s.controller_problems == 1);
  std::memset(d, 0, sizeof d);
  DecodeErrorFrame(CAN_ERR_FLAG | CAN_ERR_PROT | CAN_ERR_ACK | CAN_ERR_TX_TIMEOUT | CAN_ERR_LOSTARB, d, s);
  CHECK(s.protocol_violations == 1);
  CHECK(s.no_ack == 1);
  CHECK(s.tx_timeouts == 1);
  CHECK(s.lost_arbitration == 1);
  DecodeErrorFrame(CAN_ERR_FLAG | CAN_ERR_RESTARTED, d, s);
  CHECK(s.restarted == 1);
  CHECK_FALSE(s.is_bus_off);
  CHECK(s.error_frames == 5);
}

TEST_CASE("error frames are described in words") {
  std::uint8_t d[8] = {};
  d[1] = CAN_ERR_CRTL_TX_PASSIVE;
  char b[128];
  DescribeErrorFrame(CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_BUSOFF, d, b, sizeof b);
  CHECK(std::string(b) == "controller: tx error-passive, bus-off");
  char tiny[8];
  DescribeErrorFrame(CAN_ERR_FLAG | CAN_ERR_BUSOFF | CAN_ERR_ACK, d, tiny, sizeof tiny);
  CHECK(std::strlen(tiny) < sizeof tiny);
}
