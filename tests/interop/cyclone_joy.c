/* A ROS 2 joy node's side written against Cyclone DDS (the DDS stack of ROS 2's rmw_cyclonedds):
 * it publishes sensor_msgs::msg::dds_::Joy_ on rt/joy with ROS 2's default QoS, as
 * game_controller_node does for an Xbox-style pad (six axes, fifteen buttons, frame "joy", the
 * stamp from the clock), at its autorepeat rate of 20 Hz. The C type comes from the project's IDL
 * (models/ros2/idl/Joy_.idl) through Cyclone's idlc: sequences and a string as Cyclone lays them.
 *
 *   cyclone_joy DOMAIN [SESSION [AXES BUTTONS]]
 *
 * Waits (at most 30 s) until a reader matches, then 2 s more (the controller starts its loop),
 * then plays a session on its own clock (seconds from then). SESSION walk (the default):
 *   0.0-1.0 START (arm: stand up)       3.0-9.0 LB (the dead-man)     3.5-4.0 A (walk)
 *   4.0-8.5 left stick up 0.55 (past the dead zone of 0.1: 0.5 m/s)   (released: stand, then sit)
 *   15.0-15.5 START (stand up)          16.5-16.8 R3 (sit down)       18.5-18.8 BACK (e-stop)
 *   19.6-19.9 GUIDE (re-arm)            20.5 silence (the pad gone)
 * SESSION run (a vehicle's mission):
 *   0.0-1.0 START (run)   6.0-6.3 BACK (e-stop)   9.0-9.3 GUIDE (re-arm)   13.0-13.3 B (stop)
 *   14.0 silence
 * AXES and BUTTONS (default 6 and 15) make a pad with fewer. Prints "published N" and exits 0; 1
 * when DDS fails, 3 when no reader came. Transport: CYCLONEDDS_URI. */
#include <dds/dds.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "Joy_.h"
#include "ros2_qos.h"

enum { kA = 0, kB = 1, kBack = 4, kGuide = 5, kStart = 6, kRightStick = 8, kLeftShoulder = 9 };

static int Held(double s, double from, double to) {
  return s >= from && s < to;
}

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3 && argc != 5) {
    fprintf(stderr, "usage: cyclone_joy DOMAIN [SESSION [AXES BUTTONS]]\n");
    return 2;
  }
  const dds_domainid_t domain = (dds_domainid_t)atoi(argv[1]);
  const int walk = argc < 3 || strcmp(argv[2], "walk") == 0;
  const unsigned axes = argc == 5 ? (unsigned)atoi(argv[3]) : 6u;
  const unsigned buttons = argc == 5 ? (unsigned)atoi(argv[4]) : 15u;
  if ((!walk && strcmp(argv[2], "run") != 0) || axes > 6 || buttons > 15) {
    fprintf(stderr, "cyclone_joy: SESSION walk or run, at most 6 axes and 15 buttons\n");
    return 2;
  }
  dds_entity_t participant = 0;
  const dds_entity_t writer =
      Ros2Publisher("cyclone_joy", domain, &sensor_msgs_msg_dds__Joy__desc, "rt/joy", &participant);
  if (writer < 0) return -writer;
  dds_sleepfor(DDS_SECS(2));
  float axis[6];
  int32_t button[15];
  char frame[] = "joy";
  unsigned long long published = 0;
  const long long t0 = Ros2NowNs();
  long long next = t0;
  for (;;) {
    const double s = (double)(Ros2NowNs() - t0) * 1e-9;
    if (s >= (walk ? 20.5 : 14.0)) break;
    for (unsigned k = 0; k < 6; ++k) axis[k] = 0.0f;
    for (unsigned k = 0; k < 15; ++k) button[k] = 0;
    button[kStart] = Held(s, 0.0, 1.0);
    if (walk) {
      button[kStart] = Held(s, 0.0, 1.0) || Held(s, 15.0, 15.5);
      button[kLeftShoulder] = Held(s, 3.0, 9.0);
      button[kA] = Held(s, 3.5, 4.0);
      button[kRightStick] = Held(s, 16.5, 16.8);
      button[kBack] = Held(s, 18.5, 18.8);
      button[kGuide] = Held(s, 19.6, 19.9);
      axis[1] = Held(s, 4.0, 8.5) ? 0.55f : 0.0f;
    } else {
      button[kBack] = Held(s, 6.0, 6.3);
      button[kGuide] = Held(s, 9.0, 9.3);
      button[kB] = Held(s, 13.0, 13.3);
    }
    struct timespec wall;
    clock_gettime(CLOCK_REALTIME, &wall);
    sensor_msgs_msg_dds__Joy_ joy;
    joy.header.stamp.sec = (int32_t)wall.tv_sec;
    joy.header.stamp.nanosec = (uint32_t)wall.tv_nsec;
    joy.header.frame_id = frame;
    joy.axes._maximum = joy.axes._length = axes;
    joy.axes._buffer = axis;
    joy.axes._release = false;
    joy.buttons._maximum = joy.buttons._length = buttons;
    joy.buttons._buffer = button;
    joy.buttons._release = false;
    if (dds_write(writer, &joy) == DDS_RETCODE_OK) ++published;
    next += 50000000LL; /* 20 Hz */
    const long long wait = next - Ros2NowNs();
    if (wait > 0) dds_sleepfor(wait);
  }
  printf("published %llu\n", published);
  fflush(stdout);
  dds_delete(participant);
  return 0;
}
