/*
 * can_smoke: checks that SocketCAN works on an interface (default vcan0).
 * Two raw CAN sockets with CAN_RAW_FD_FRAMES on; one sends a classic frame and
 * a CAN FD frame, the other receives both and checks them. Prints the round
 * trip (send -> receive) times. Exit 0 on success.
 *
 *   gcc -O2 -Wall -o /tmp/can_smoke tests/vm/can_smoke.c
 *   tests/vm/vcan-vm /tmp/can_smoke [ifname]
 */
#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static double now_us(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1e6 + ts.tv_nsec / 1e3;
}

static int open_can(const char *ifname) {
  int s = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s < 0) {
    perror("socket(PF_CAN)");
    return -1;
  }
  int on = 1;
  if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0) {
    perror("setsockopt(CAN_RAW_FD_FRAMES)");
    return -1;
  }
  struct sockaddr_can addr = {.can_family = AF_CAN, .can_ifindex = (int)if_nametoindex(ifname)};
  if (addr.can_ifindex == 0) {
    fprintf(stderr, "no interface %s\n", ifname);
    return -1;
  }
  if (bind(s, (struct sockaddr *)&addr, sizeof addr) < 0) {
    perror("bind");
    return -1;
  }
  return s;
}

/* Receive one frame within 1 s; returns its size (CAN_MTU or CANFD_MTU). */
static int recv_frame(int s, struct canfd_frame *f) {
  struct pollfd p = {.fd = s, .events = POLLIN};
  if (poll(&p, 1, 1000) != 1) {
    fprintf(stderr, "timeout waiting for a frame\n");
    return -1;
  }
  ssize_t n = read(s, f, sizeof *f);
  if (n < 0) perror("read");
  return (int)n;
}

int main(int argc, char **argv) {
  const char *ifname = argc > 1 ? argv[1] : "vcan0";
  int tx = open_can(ifname);
  if (tx < 0) return 1;
  int rx = open_can(ifname);
  if (rx < 0) return 1;

  /* classic CAN frame */
  struct can_frame cf = {.can_id = 0x123, .can_dlc = 8};
  memcpy(cf.data, "\x01\x02\x03\x04\x05\x06\x07\x08", 8);
  /* CAN FD frame, 64 bytes, bit rate switch */
  struct canfd_frame fd = {.can_id = 0x456 | CAN_EFF_FLAG, .len = 64, .flags = CANFD_BRS};
  for (int i = 0; i < 64; i++) fd.data[i] = (unsigned char)(i * 3 + 1);

  struct canfd_frame got;
  double t0 = now_us();
  if (write(tx, &cf, CAN_MTU) != CAN_MTU) {
    perror("write classic");
    return 1;
  }
  int n = recv_frame(rx, &got);
  double rtt_classic = now_us() - t0;
  if (n != CAN_MTU || got.can_id != cf.can_id || got.len != 8 || memcmp(got.data, cf.data, 8) != 0) {
    fprintf(stderr, "classic frame mismatch (size %d, id 0x%x, len %u)\n", n, got.can_id, got.len);
    return 1;
  }

  t0 = now_us();
  if (write(tx, &fd, CANFD_MTU) != CANFD_MTU) {
    perror("write fd");
    return 1;
  }
  n = recv_frame(rx, &got);
  double rtt_fd = now_us() - t0;
  if (n != CANFD_MTU || got.can_id != fd.can_id || got.len != 64 || !(got.flags & CANFD_BRS) ||
      memcmp(got.data, fd.data, 64) != 0) {
    fprintf(stderr, "CAN FD frame mismatch (size %d, id 0x%x, len %u)\n", n, got.can_id, got.len);
    return 1;
  }

  /* median of 1000 classic round trips */
  enum { N = 1000 };
  static double rtt[N];
  for (int i = 0; i < N; i++) {
    cf.data[0] = (unsigned char)i;
    t0 = now_us();
    if (write(tx, &cf, CAN_MTU) != CAN_MTU || recv_frame(rx, &got) != CAN_MTU || got.data[0] != cf.data[0]) {
      fprintf(stderr, "round trip %d failed\n", i);
      return 1;
    }
    rtt[i] = now_us() - t0;
  }
  for (int i = 1; i < N; i++) /* insertion sort, N is small */
    for (int j = i; j > 0 && rtt[j - 1] > rtt[j]; j--) {
      double t = rtt[j];
      rtt[j] = rtt[j - 1];
      rtt[j - 1] = t;
    }

  printf("can_smoke %s: classic OK (%.1f us), CAN FD OK (%.1f us), rtt median %.1f us p99 %.1f us over %d\n",
         ifname, rtt_classic, rtt_fd, rtt[N / 2], rtt[N * 99 / 100], N);
  close(tx);
  close(rx);
  return 0;
}
