/* For the test programs that stand in for ROS 2 nodes on Cyclone DDS: the QoS a ROS 2 node's
 * publishers and subscriptions use by default (rmw's "default" profile: reliable, volatile, keep
 * last 10), and a publisher of one topic with it that waits for a reader. */
#pragma once

#include <dds/dds.h>
#include <stdio.h>
#include <time.h>

/* The caller deletes it (dds_delete_qos). */

static inline dds_qos_t* Ros2DefaultQos(void) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
  return qos;
}

static inline long long Ros2NowNs(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}

/* A participant on `domain` (into *participant) and a writer of `topic` with ROS 2's default QoS,
 * once a reader matched (at most 30 s). Returns the writer; on failure says why on stderr, prefixed
 * by `program`, deletes the participant and returns -1 (DDS failed) or -3 (no reader came). */
static inline dds_entity_t Ros2Publisher(const char* program, dds_domainid_t domain, const dds_topic_descriptor_t* type,
                                         const char* topic, dds_entity_t* participant) {
  *participant = dds_create_participant(domain, NULL, NULL);
  if (*participant < 0) {
    fprintf(stderr, "%s: dds_create_participant: %s\n", program, dds_strretcode(-*participant));
    return -1;
  }
  const dds_entity_t t = dds_create_topic(*participant, type, topic, NULL, NULL);
  dds_qos_t* qos = Ros2DefaultQos();
  const dds_entity_t writer = t < 0 ? t : dds_create_writer(*participant, t, qos, NULL);
  dds_delete_qos(qos);
  if (writer < 0) {
    fprintf(stderr, "%s: %s: %s\n", program, t < 0 ? "dds_create_topic" : "dds_create_writer", dds_strretcode(-writer));
    dds_delete(*participant);
    return -1;
  }
  dds_publication_matched_status_t matched = {0};
  const long long wait_end = Ros2NowNs() + 30000000000LL;
  while (matched.current_count == 0 && Ros2NowNs() < wait_end) {
    dds_get_publication_matched_status(writer, &matched);
    dds_sleepfor(DDS_MSECS(5));
  }
  if (matched.current_count == 0) {
    fprintf(stderr, "%s: no reader of %s within 30 s\n", program, topic);
    dds_delete(*participant);
    return -3;
  }
  return writer;
}
