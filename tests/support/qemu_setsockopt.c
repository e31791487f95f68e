// Loaded (LD_PRELOAD, through qemu-aarch64 -E) into the test programs of a cross-build that run
// under Debian 12's qemu-user 7.2, and nowhere else. That qemu does not translate
// setsockopt(IPPROTO_IP, IP_MULTICAST_IF) and fails it with ENOPROTOOPT; Fast DDS sets that option
// on every UDP socket it sends from, and gives up the socket when it fails, so no participant
// would ever discover another. The robots' profile (models/dds_profile.xml) sends unicast on the
// loopback interface only, where the multicast interface plays no part: the call is reported as
// done. Every other call, and every other failure, goes through unchanged. On an arm64 board the
// option works and nothing is preloaded.
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <netinet/in.h>
#include <sys/socket.h>

typedef int (*SetSockOpt)(int, int, int, const void*, socklen_t);

int setsockopt(int fd, int level, int name, const void* value, socklen_t size) {
  static SetSockOpt real = 0;
  if (real == 0) real = (SetSockOpt)dlsym(RTLD_NEXT, "setsockopt");
  const int rc = real(fd, level, name, value, size);
  if (rc != 0 && errno == ENOPROTOOPT && level == IPPROTO_IP && name == IP_MULTICAST_IF) {
    errno = 0;
    return 0;
  }
  return rc;
}
