/* A ROS 2 node's side of cmd_vel written against Cyclone DDS (the DDS stack of ROS 2's
 * rmw_cyclonedds): it publishes geometry_msgs::msg::dds_::Twist_ on rt/cmd_vel with ROS 2's
 * default QoS. The C type comes from the project's IDL (models/ros2/idl/Twist_.idl) through
 * Cyclone's idlc.
 *
 *   cyclone_cmd_vel DOMAIN
 *
 * Waits (at most 30 s) until a reader matches, then plays a fixed script on its own clock from
 * that moment: linear.x 0 until 2.5 s, 0.5 m/s until 5.9 s at 20 Hz, one last Twist of 0.45 m/s
 * (a value the controller's trace can tell apart), silence, one Twist with a NaN at 8.5 s,
 * silence until 9.5 s. Prints "published N" and exits 0; 1 when DDS fails, 3 when no reader came.
 * Transport: CYCLONEDDS_URI (the test sets loopback, unicast discovery to 127.0.0.1). */
#include <dds/dds.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "Twist_.h"
#include "ros2_qos.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: cyclone_cmd_vel DOMAIN\n");
    return 2;
  }
  const dds_domainid_t domain = (dds_domainid_t)atoi(argv[1]);
  dds_entity_t participant = 0;
  const dds_entity_t writer =
      Ros2Publisher("cyclone_cmd_vel", domain, &geometry_msgs_msg_dds__Twist__desc, "rt/cmd_vel", &participant);
  if (writer < 0) return -writer;
  unsigned long long published = 0;
  int last_sent = 0, nan_sent = 0;
  const long long t0 = Ros2NowNs();
  long long next = t0;
  for (;;) {
    const double s = (double)(Ros2NowNs() - t0) * 1e-9;
    if (s >= 9.5) break;
    geometry_msgs_msg_dds__Twist_ twist = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    int send = 1;
    if (s < 5.9) {
      twist.linear.x = s < 2.5 ? 0.0 : 0.5;
    } else if (!last_sent) {
      twist.linear.x = 0.45;
      last_sent = 1;
    } else if (s >= 8.5 && !nan_sent) {
      twist.linear.x = NAN;
      nan_sent = 1;
    } else {
      send = 0;
    }
    if (send && dds_write(writer, &twist) == DDS_RETCODE_OK) ++published;
    next += 50000000LL; /* 20 Hz */
    const long long wait = next - Ros2NowNs();
    if (wait > 0) dds_sleepfor(wait);
  }
  printf("published %llu\n", published);
  fflush(stdout);
  dds_delete(participant);
  return 0;
}
