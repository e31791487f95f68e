/* The Unitree Go2's side of its low-level DDS interface, written against Cyclone DDS (what the
 * robot itself runs): it publishes rt/lowstate (unitree_go::msg::dds_::LowState_) and reads
 * rt/lowcmd (unitree_go::msg::dds_::LowCmd_), both final structs whose C types come from the
 * project's IDL (models/go2/idl/) through Cyclone's idlc, so a controller can be tested against a
 * second, independent implementation of the wire format and of the CRC.
 *
 *   cyclone_go2_robot DOMAIN SECONDS [--rate HZ] [--pose q0,...,q11] [--bad-crc-every N]
 *                     [--kp-max X] [--kd-max X] [--tau-max X] [--no-type-info]
 *
 * For SECONDS it publishes LowState_ at HZ (500) with a correct CRC, `tick` counting the samples
 * published (1, 2, ...), the 12 leg motors (FR, FL, RR, RL; hip, thigh, calf) in servo mode held
 * at the pose (default: the Go2's stand pose of its RL configs) with zero velocity and torque, and
 * the IMU level (quaternion w, x, y, z = 1, 0, 0, 0; gravity +9.81 on z). --bad-crc-every N: every
 * Nth LowState_ carries a wrong CRC (for a test of the controller's refusal).
 * Each LowCmd_ taken is checked: its CRC; head 0xFE, 0xEF; level_flag 0xFF; every leg motor's q,
 * dq, tau, kp, kd finite, 0 <= kp <= kp-max (100), 0 <= kd <= kd-max (10), |tau| <= tau-max (the
 * published motor limits: 23.7 N m hip and thigh, 45.43 N m calf), and q within the joint's range
 * when kp > 0 (with kp = 0 the position term is off and q may be PosStopF, as in Unitree's
 * examples). The first few failures go to stderr. At the end it prints:
 *   lowstate published N bad_crc N
 *   lowcmd received N crc_ok N crc_bad N
 *   lowcmd checks head_bad N level_flag_bad N bounds_bad N
 *   last lowcmd motor0 mode=M q=Q dq=DQ kp=KP kd=KD tau=TAU   (when one was received)
 * Exit 0 when at least one LowCmd_ was received and every check passed; 3 when none was received,
 * 4 on a CRC mismatch, 5 on another failed check; 2 on bad usage, 1 when DDS cannot be set up.
 * --no-type-info: publish the types without XTypes type information (matched on the name only).
 * Transport: CYCLONEDDS_URI (the tests set loopback, unicast discovery to 127.0.0.1).
 *
 * The CRC here is written from the algorithm's definition, independently of the controller's C++
 * (runtime/): CRC-32/MPEG-2 (polynomial 0x04C11DB7, initial value 0xFFFFFFFF, no reflection, no
 * final XOR) over the message as a packed little-endian C struct with natural alignment (LowCmd_
 * 812 bytes, LowState_ 1180), read as 32-bit little-endian words, every word but the last (the crc
 * itself), each word fed most significant bit first. tests/data/go2/crc_oracle.py is a third,
 * Python, implementation of the same. */
#include <dds/dds.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "LowCmd_.h"
#include "LowState_.h"

typedef unitree_go_msg_dds__LowCmd_ LowCmd;
typedef unitree_go_msg_dds__LowState_ LowState;

/* The idlc C structs, laid out by this compiler, are the packed layout the CRC covers (natural
 * alignment, little-endian host): checked here, so the CRC can run over the struct's own bytes.
 * Padding bytes count in the CRC and are zero on the robot's side: every struct is zeroed before
 * it is filled or taken into. */
#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the CRC is taken over the struct's bytes as little-endian words: a little-endian host is needed"
#endif
_Static_assert(sizeof(struct unitree_go_msg_dds__MotorCmd_) == 36, "MotorCmd_ packs to 36 bytes");
_Static_assert(sizeof(struct unitree_go_msg_dds__MotorState_) == 48, "MotorState_ packs to 48 bytes");
_Static_assert(sizeof(struct unitree_go_msg_dds__IMUState_) == 56, "IMUState_ packs to 56 bytes");
_Static_assert(sizeof(struct unitree_go_msg_dds__BmsState_) == 44, "BmsState_ packs to 44 bytes");
_Static_assert(sizeof(LowCmd) == 812, "LowCmd_ packs to 812 bytes");
_Static_assert(offsetof(LowCmd, bandwidth) == 20 && offsetof(LowCmd, motor_cmd) == 24 &&
                   offsetof(LowCmd, bms_cmd) == 744 && offsetof(LowCmd, wireless_remote) == 748 &&
                   offsetof(LowCmd, gpio) == 802 && offsetof(LowCmd, reserve) == 804 && offsetof(LowCmd, crc) == 808,
               "LowCmd_ member offsets as packed");
_Static_assert(offsetof(struct unitree_go_msg_dds__MotorCmd_, q) == 4 &&
                   offsetof(struct unitree_go_msg_dds__MotorCmd_, reserve) == 24,
               "MotorCmd_ member offsets as packed");
_Static_assert(sizeof(LowState) == 1180, "LowState_ packs to 1180 bytes");
_Static_assert(offsetof(LowState, imu_state) == 24 && offsetof(LowState, motor_state) == 80 &&
                   offsetof(LowState, bms_state) == 1040 && offsetof(LowState, foot_force) == 1084 &&
                   offsetof(LowState, tick) == 1100 && offsetof(LowState, wireless_remote) == 1104 &&
                   offsetof(LowState, bit_flag) == 1144 && offsetof(LowState, adc_reel) == 1148 &&
                   offsetof(LowState, temperature_ntc1) == 1152 && offsetof(LowState, power_v) == 1156 &&
                   offsetof(LowState, fan_frequency) == 1164 && offsetof(LowState, reserve) == 1172 &&
                   offsetof(LowState, crc) == 1176,
               "LowState_ member offsets as packed");
_Static_assert(offsetof(struct unitree_go_msg_dds__MotorState_, temperature) == 32 &&
                   offsetof(struct unitree_go_msg_dds__MotorState_, lost) == 36,
               "MotorState_ member offsets as packed");
_Static_assert(offsetof(struct unitree_go_msg_dds__BmsState_, current) == 4 &&
                   offsetof(struct unitree_go_msg_dds__BmsState_, cell_vol) == 14,
               "BmsState_ member offsets as packed");

/* CRC-32/MPEG-2 fed 32-bit words, each from bit 31 down to bit 0. */
static uint32_t Crc32Mpeg2Words(const uint32_t* words, size_t n) {
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    crc ^= words[i];
    for (int b = 0; b < 32; ++b) crc = (crc & 0x80000000u) ? (crc << 1) ^ 0x04C11DB7u : crc << 1;
  }
  return crc;
}

/* The Go2's CRC of a packed message of `size` bytes (a multiple of 4): every word but the last. */
static uint32_t Go2Crc(const void* packed, size_t size) {
  uint32_t words[1180 / 4];
  const size_t n = size / 4 - 1;
  memcpy(words, packed, n * 4); /* little-endian host: each word as read little-endian */
  return Crc32Mpeg2Words(words, n);
}

/* The register against the catalogue: CRC-32/MPEG-2 of the ASCII bytes "123456789", fed byte-wise
 * MSB first, is 0x0376E6E7. Fed MSB first, a 32-bit word is the same bit stream as its four bytes in
 * big-endian order, so the word-wise CRC of "1234" "5678" read as big-endian words equals the
 * byte-wise CRC of "12345678": checked too. */
static int CrcSelfCheck(void) {
  const unsigned char s[] = "123456789";
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = 0; i < 9; ++i) {
    crc ^= (uint32_t)s[i] << 24;
    for (int b = 0; b < 8; ++b) crc = (crc & 0x80000000u) ? (crc << 1) ^ 0x04C11DB7u : crc << 1;
  }
  /* The word-wise register over "12345678" as two big-endian words equals the byte-wise one. */
  const uint32_t words[2] = {0x31323334u, 0x35363738u};
  uint32_t bytewise = 0xFFFFFFFFu;
  for (size_t i = 0; i < 8; ++i) {
    bytewise ^= (uint32_t)s[i] << 24;
    for (int b = 0; b < 8; ++b) bytewise = (bytewise & 0x80000000u) ? (bytewise << 1) ^ 0x04C11DB7u : bytewise << 1;
  }
  return crc == 0x0376E6E7u && Crc32Mpeg2Words(words, 2) == bytewise;
}

/* The descriptor without XTypes type information (matched on the type name only). */
static dds_topic_descriptor_t WithoutTypeInfo(const dds_topic_descriptor_t* d) {
  dds_topic_descriptor_t r = {.m_size = d->m_size,
                              .m_align = d->m_align,
                              .m_flagset = d->m_flagset & ~(uint32_t)DDS_TOPIC_XTYPES_METADATA,
                              .m_nkeys = d->m_nkeys,
                              .m_typename = d->m_typename,
                              .m_keys = d->m_keys,
                              .m_nops = d->m_nops,
                              .m_ops = d->m_ops,
                              .m_meta = d->m_meta,
                              .type_information = {NULL, 0},
                              .type_mapping = {NULL, 0},
                              .restrict_data_representation = d->restrict_data_representation};
  return r;
}

static long long NowNs(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}

static void SleepUntilNs(long long t) {
  struct timespec ts = {.tv_sec = (time_t)(t / 1000000000LL), .tv_nsec = (long)(t % 1000000000LL)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) != 0) {
  }
}

/* Joint ranges (rad) and torque limits (N m) by leg (FR, FL, RR, RL) and joint (hip, thigh, calf),
 * as published for the Go2. */
static const double kQMin[4][3] = {
    {-1.05, -1.57, -2.72}, {-1.05, -1.57, -2.72}, {-1.05, -0.52, -2.72}, {-1.05, -0.52, -2.72}};
static const double kQMax[4][3] = {{1.05, 3.49, -0.84}, {1.05, 3.49, -0.84}, {1.05, 4.54, -0.84}, {1.05, 4.54, -0.84}};
static const double kTauMax[3] = {23.7, 23.7, 45.43};

typedef struct {
  double kp_max, kd_max, tau_max; /* tau_max < 0: the per-joint limits */
} Bounds;

typedef struct {
  unsigned long long received, crc_ok, crc_bad, head_bad, level_bad, bounds_bad;
  int reported;
} CmdStats;

__attribute__((format(printf, 2, 3))) static void Report(CmdStats* s, const char* fmt, ...) {
  if (s->reported >= 10) return;
  ++s->reported;
  fprintf(stderr, "cyclone_go2_robot: lowcmd #%llu: ", s->received);
  va_list args;
  va_start(args, fmt);
  vfprintf(stderr, fmt, args);
  va_end(args);
  fputc('\n', stderr);
}

static void CheckCommand(const LowCmd* c, const Bounds* b, CmdStats* s) {
  ++s->received;
  const uint32_t crc = Go2Crc(c, sizeof *c);
  if (crc == c->crc) {
    ++s->crc_ok;
  } else {
    ++s->crc_bad;
    Report(s, "crc 0x%08x, computed 0x%08x", (unsigned)c->crc, (unsigned)crc);
  }
  if (c->head[0] != 0xFE || c->head[1] != 0xEF) {
    ++s->head_bad;
    Report(s, "head 0x%02x 0x%02x, not 0xFE 0xEF", (unsigned)c->head[0], (unsigned)c->head[1]);
  }
  if (c->level_flag != 0xFF) {
    ++s->level_bad;
    Report(s, "level_flag 0x%02x, not 0xFF", (unsigned)c->level_flag);
  }
  int bad = 0;
  for (int m = 0; m < 12; ++m) {
    const struct unitree_go_msg_dds__MotorCmd_* mc = &c->motor_cmd[m];
    const int leg = m / 3, joint = m % 3;
    const double tau_max = b->tau_max >= 0 ? b->tau_max : kTauMax[joint];
    if (!isfinite(mc->q) || !isfinite(mc->dq) || !isfinite(mc->tau) || !isfinite(mc->kp) || !isfinite(mc->kd)) {
      Report(s, "motor %d: a non-finite q, dq, tau, kp or kd", m);
      bad = 1;
      continue;
    }
    if (mc->kp < 0 || mc->kp > b->kp_max) {
      Report(s, "motor %d: kp %g out of bounds", m, (double)mc->kp);
      bad = 1;
    }
    if (mc->kd < 0 || mc->kd > b->kd_max) {
      Report(s, "motor %d: kd %g out of bounds", m, (double)mc->kd);
      bad = 1;
    }
    if (fabs(mc->tau) > tau_max) {
      Report(s, "motor %d: tau %g out of bounds", m, (double)mc->tau);
      bad = 1;
    }
    if (mc->kp > 0 && (mc->q < kQMin[leg][joint] || mc->q > kQMax[leg][joint])) {
      Report(s, "motor %d: q %g outside the joint's range", m, (double)mc->q);
      bad = 1;
    }
  }
  if (bad) ++s->bounds_bad;
}

static int ParsePose(const char* text, double pose[12]) {
  for (int i = 0; i < 12; ++i) {
    char* end = NULL;
    pose[i] = strtod(text, &end);
    if (end == text || (i < 11 && *end != ',') || (i == 11 && *end != '\0')) return 0;
    text = end + 1;
  }
  return 1;
}

static int Usage(void) {
  fprintf(stderr,
          "usage: cyclone_go2_robot DOMAIN SECONDS [--rate HZ] [--pose q0,...,q11] [--bad-crc-every N]\n"
          "                         [--kp-max X] [--kd-max X] [--tau-max X] [--no-type-info]\n");
  return 2;
}

int main(int argc, char** argv) {
  if (argc < 3) return Usage();
  const dds_domainid_t domain = (dds_domainid_t)atoi(argv[1]);
  const double seconds = atof(argv[2]);
  double rate_hz = 500.0;
  long bad_crc_every = 0;
  int type_info = 1;
  Bounds bounds = {.kp_max = 100.0, .kd_max = 10.0, .tau_max = -1.0};
  /* The stand pose of the Go2's RL configs (unitree_rl_gym): hips +-0.1, thighs 0.8 front and 1.0
   * rear, calves -1.5; legs FR, FL, RR, RL. */
  double pose[12] = {-0.1, 0.8, -1.5, 0.1, 0.8, -1.5, -0.1, 1.0, -1.5, 0.1, 1.0, -1.5};
  for (int i = 3; i < argc; ++i) {
    const char* a = argv[i];
    if (strcmp(a, "--no-type-info") == 0) {
      type_info = 0;
      continue;
    }
    if (i + 1 >= argc) return Usage();
    const char* v = argv[++i];
    if (strcmp(a, "--rate") == 0)
      rate_hz = atof(v);
    else if (strcmp(a, "--bad-crc-every") == 0)
      bad_crc_every = atol(v);
    else if (strcmp(a, "--kp-max") == 0)
      bounds.kp_max = atof(v);
    else if (strcmp(a, "--kd-max") == 0)
      bounds.kd_max = atof(v);
    else if (strcmp(a, "--tau-max") == 0)
      bounds.tau_max = atof(v);
    else if (strcmp(a, "--pose") == 0) {
      if (!ParsePose(v, pose)) return Usage();
    } else
      return Usage();
  }
  if (!(rate_hz > 0) || !(seconds >= 0) || bad_crc_every < 0) return Usage();
  if (!CrcSelfCheck()) {
    fprintf(stderr, "cyclone_go2_robot: the CRC fails its check value\n");
    return 1;
  }

  const dds_topic_descriptor_t state_desc =
      type_info ? unitree_go_msg_dds__LowState__desc : WithoutTypeInfo(&unitree_go_msg_dds__LowState__desc);
  const dds_topic_descriptor_t cmd_desc =
      type_info ? unitree_go_msg_dds__LowCmd__desc : WithoutTypeInfo(&unitree_go_msg_dds__LowCmd__desc);
  const dds_entity_t participant = dds_create_participant(domain, NULL, NULL);
  if (participant < 0) {
    fprintf(stderr, "cyclone_go2_robot: dds_create_participant: %s\n", dds_strretcode(-participant));
    return 1;
  }
  const dds_entity_t state_topic = dds_create_topic(participant, &state_desc, "rt/lowstate", NULL, NULL);
  const dds_entity_t cmd_topic = dds_create_topic(participant, &cmd_desc, "rt/lowcmd", NULL, NULL);
  if (state_topic < 0 || cmd_topic < 0) {
    fprintf(stderr, "cyclone_go2_robot: dds_create_topic failed\n");
    dds_delete(participant);
    return 1;
  }
  /* The writer offers reliable (matches best-effort and reliable readers), the reader asks only
   * best effort (matches either kind of writer); keep last 1: only the newest sample matters. */
  dds_qos_t* qos = dds_create_qos();
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(10));
  const dds_entity_t writer = dds_create_writer(participant, state_topic, qos, NULL);
  dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 16);
  const dds_entity_t reader = dds_create_reader(participant, cmd_topic, qos, NULL);
  dds_delete_qos(qos);
  if (writer < 0 || reader < 0) {
    fprintf(stderr, "cyclone_go2_robot: cannot create the writer or the reader\n");
    dds_delete(participant);
    return 1;
  }

  static LowState state;
  memset(&state, 0, sizeof state);
  state.head[0] = 0xFE;
  state.head[1] = 0xEF;
  state.level_flag = 0xFF;
  state.imu_state.quaternion[0] = 1.0f;
  state.imu_state.accelerometer[2] = 9.81f;
  state.imu_state.temperature = 30;
  for (int m = 0; m < 12; ++m) {
    state.motor_state[m].mode = 0x01;
    state.motor_state[m].q = (float)pose[m];
    state.motor_state[m].q_raw = (float)pose[m];
    state.motor_state[m].temperature = 30;
  }
  state.bms_state.soc = 90;
  state.power_v = 28.0f;
  for (int f = 0; f < 4; ++f) state.foot_force[f] = 30;

  CmdStats stats;
  memset(&stats, 0, sizeof stats);
  static LowCmd last;
  memset(&last, 0, sizeof last);
  unsigned long long published = 0, published_bad = 0;
  const long long period = (long long)(1e9 / rate_hz);
  const long long t0 = NowNs(), end = t0 + (long long)(seconds * 1e9);
  long long next = t0;
  while (NowNs() < end) {
    if (NowNs() >= next) {
      state.tick = (uint32_t)(published + 1);
      state.crc = Go2Crc(&state, sizeof state);
      const int bad = bad_crc_every > 0 && (published + 1) % (unsigned long long)bad_crc_every == 0;
      if (bad) state.crc ^= 0x00000001u;
      if (dds_write(writer, &state) == DDS_RETCODE_OK) {
        ++published;
        if (bad) ++published_bad;
      }
      next += period;
      if (next < NowNs()) next = NowNs() + period; /* fell behind: no burst to catch up */
    }
    for (;;) {
      static LowCmd buf;
      memset(&buf, 0, sizeof buf); /* padding zero, as the packed layout has it */
      void* samples[1] = {&buf};
      dds_sample_info_t info[1];
      if (dds_take(reader, samples, info, 1, 1) <= 0) break;
      if (!info[0].valid_data) continue;
      CheckCommand(&buf, &bounds, &stats);
      last = buf;
    }
    const long long wake = NowNs() + 1000000LL; /* poll commands at least every 1 ms */
    SleepUntilNs(next < wake ? next : wake);
  }

  printf("lowstate published %llu bad_crc %llu\n", published, published_bad);
  printf("lowcmd received %llu crc_ok %llu crc_bad %llu\n", stats.received, stats.crc_ok, stats.crc_bad);
  printf("lowcmd checks head_bad %llu level_flag_bad %llu bounds_bad %llu\n", stats.head_bad, stats.level_bad,
         stats.bounds_bad);
  if (stats.received > 0)
    printf("last lowcmd motor0 mode=%u q=%.4f dq=%.4f kp=%.3f kd=%.3f tau=%.4f\n", (unsigned)last.motor_cmd[0].mode,
           last.motor_cmd[0].q, last.motor_cmd[0].dq, last.motor_cmd[0].kp, last.motor_cmd[0].kd,
           last.motor_cmd[0].tau);
  fflush(stdout);
  dds_delete(participant);
  if (stats.received == 0) return 3;
  if (stats.crc_bad > 0) return 4;
  if (stats.head_bad > 0 || stats.level_bad > 0 || stats.bounds_bad > 0) return 5;
  return 0;
}
