/* The QoS a ROS 2 node's publishers and subscriptions use by default (rmw's "default" profile:
 * reliable, volatile, keep last 10), for the test programs that stand in for ROS 2 nodes.
 * The caller deletes it (dds_delete_qos). */
#pragma once

#include <dds/dds.h>

static inline dds_qos_t* Ros2DefaultQos(void) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
  return qos;
}
