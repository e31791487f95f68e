/* A quadruped operator written against Cyclone DDS (a second DDS implementation), speaking ROS 2's
 * names: it publishes velocity commands on rt/pbppo/quadruped/velocity_command as
 * pbppo_msgs::msg::dds_::VelocityCommand_ and reads the controller's status from
 * rt/pbppo/quadruped/status (pbppo_msgs::msg::dds_::QuadrupedStatus_), as a ROS 2 node would.
 * The C types come from the project's IDL (models/quadruped/idl/) through Cyclone's idlc.
 *
 *   cyclone_operator DOMAIN VX SECONDS LINGER_SECONDS
 *
 * Publishes {vx, 0, 0} at 20 Hz for SECONDS, then only listens for LINGER_SECONDS. Prints one
 * line per phase: "commanding <status>" (the last status while commanding) and "after <status>"
 * (the last status after it stopped), and "published N". Exit 0 when a status was received.
 * Transport: CYCLONEDDS_URI (the test sets loopback, unicast discovery to 127.0.0.1). */
#include <dds/dds.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "QuadrupedStatus.h"
#include "VelocityCommand.h"
#include "ros2_qos.h"

/* The descriptor under another type name (ROS 2's), without the XTypes type information that
 * names the IDL's type: the remote side matches on the name. */
static dds_topic_descriptor_t Renamed(const dds_topic_descriptor_t* d, const char* name) {
  dds_topic_descriptor_t r = {.m_size = d->m_size,
                              .m_align = d->m_align,
                              .m_flagset = d->m_flagset & ~(uint32_t)DDS_TOPIC_XTYPES_METADATA,
                              .m_nkeys = d->m_nkeys,
                              .m_typename = name,
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

static void PrintStatus(const char* what, const pbppo_idl_quadruped_QuadrupedStatus* s) {
  printf("%s tick=%llu phase=%u mode=%u cause=%u commands=%llu vx=%.4f vy=%.4f yaw_rate=%.4f\n", what,
         (unsigned long long)s->tick, (unsigned)s->phase, (unsigned)s->mode, (unsigned)s->cause,
         (unsigned long long)s->commands_received, s->command_vx_mps, s->command_vy_mps, s->command_yaw_rate_radps);
  fflush(stdout);
}

int main(int argc, char** argv) {
  if (argc != 5) {
    fprintf(stderr, "usage: cyclone_operator DOMAIN VX SECONDS LINGER_SECONDS\n");
    return 2;
  }
  const dds_domainid_t domain = (dds_domainid_t)atoi(argv[1]);
  const double vx = atof(argv[2]), seconds = atof(argv[3]), linger = atof(argv[4]);
  const dds_topic_descriptor_t command_desc =
      Renamed(&pbppo_idl_quadruped_VelocityCommand_desc, "pbppo_msgs::msg::dds_::VelocityCommand_");
  const dds_topic_descriptor_t status_desc =
      Renamed(&pbppo_idl_quadruped_QuadrupedStatus_desc, "pbppo_msgs::msg::dds_::QuadrupedStatus_");

  const dds_entity_t participant = dds_create_participant(domain, NULL, NULL);
  if (participant < 0) {
    fprintf(stderr, "cyclone_operator: dds_create_participant: %s\n", dds_strretcode(-participant));
    return 1;
  }
  const dds_entity_t command_topic =
      dds_create_topic(participant, &command_desc, "rt/pbppo/quadruped/velocity_command", NULL, NULL);
  const dds_entity_t status_topic =
      dds_create_topic(participant, &status_desc, "rt/pbppo/quadruped/status", NULL, NULL);
  if (command_topic < 0 || status_topic < 0) {
    fprintf(stderr, "cyclone_operator: dds_create_topic failed\n");
    return 1;
  }
  dds_qos_t* qos = Ros2DefaultQos();
  const dds_entity_t writer = dds_create_writer(participant, command_topic, qos, NULL);
  const dds_entity_t reader = dds_create_reader(participant, status_topic, qos, NULL);
  dds_delete_qos(qos);
  if (writer < 0 || reader < 0) {
    fprintf(stderr, "cyclone_operator: cannot create the writer or the reader\n");
    return 1;
  }

  pbppo_idl_quadruped_QuadrupedStatus last;
  memset(&last, 0, sizeof last);
  int have = 0;
  unsigned long long published = 0;
  const long long t0 = NowNs();
  const long long stop_commanding = t0 + (long long)(seconds * 1e9), end = stop_commanding + (long long)(linger * 1e9);
  long long next = t0;
  int commanding = 1;
  while (NowNs() < end) {
    const long long now = NowNs();
    if (commanding && now >= stop_commanding) {
      commanding = 0;
      if (have) PrintStatus("commanding", &last);
    }
    if (commanding && now >= next) {
      pbppo_idl_quadruped_VelocityCommand c = {
          .seq = published + 1, .stamp_ns = now, .vx_mps = vx, .vy_mps = 0.0, .yaw_rate_radps = 0.0};
      if (dds_write(writer, &c) == DDS_RETCODE_OK) ++published;
      next += 50000000LL; /* 20 Hz */
    }
    void* samples[1] = {NULL};
    dds_sample_info_t info[1];
    pbppo_idl_quadruped_QuadrupedStatus buf;
    samples[0] = &buf;
    while (dds_take(reader, samples, info, 1, 1) > 0)
      if (info[0].valid_data) {
        last = buf;
        have = 1;
      }
    dds_sleepfor(DDS_MSECS(5));
  }
  if (have) PrintStatus("after", &last);
  printf("published %llu\n", published);
  fflush(stdout);
  dds_delete(participant);
  return have ? 0 : 3;
}
