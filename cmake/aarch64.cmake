# Cross-building for arm64 (aarch64 Linux: Jetson, Raspberry Pi, RK3588, i.MX 8) with Debian's
# g++-aarch64-linux-gnu, against an arm64 root made by tools/arm64/make_root.sh (the arm64
# packages of our dependencies, unpacked beside the machine's own). Tests run under qemu-aarch64
# with that root (CMAKE_CROSSCOMPILING_EMULATOR: ctest and doctest's discovery go through it).
#
#   cmake --preset arm64      (PBPPO_ARM64_ROOT: the root; default build/arm64-root)
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

if(NOT PBPPO_ARM64_ROOT)
  if(DEFINED ENV{PBPPO_ARM64_ROOT})
    set(PBPPO_ARM64_ROOT "$ENV{PBPPO_ARM64_ROOT}")
  else()
    set(PBPPO_ARM64_ROOT "${CMAKE_CURRENT_LIST_DIR}/../build/arm64-root")
  endif()
endif()
get_filename_component(PBPPO_ARM64_ROOT "${PBPPO_ARM64_ROOT}" ABSOLUTE)
if(NOT EXISTS "${PBPPO_ARM64_ROOT}/usr/lib/aarch64-linux-gnu/libc.so")
  message(FATAL_ERROR "PBPPO_ARM64_ROOT: '${PBPPO_ARM64_ROOT}' is not an arm64 root (no usr/lib/aarch64-linux-gnu/libc.so); "
                      "make it with tools/arm64/make_root.sh ${PBPPO_ARM64_ROOT}")
endif()
set(PBPPO_ARM64_ROOT "${PBPPO_ARM64_ROOT}" CACHE PATH "The arm64 root (tools/arm64/make_root.sh)" FORCE)
# try_compile projects read the root from the environment.
set(ENV{PBPPO_ARM64_ROOT} "${PBPPO_ARM64_ROOT}")

set(CMAKE_SYSROOT "${PBPPO_ARM64_ROOT}")
set(CMAKE_FIND_ROOT_PATH "${PBPPO_ARM64_ROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)  # host tools: fastddsgen, python3, git
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

find_program(PBPPO_QEMU_AARCH64 NAMES qemu-aarch64 qemu-aarch64-static)
if(PBPPO_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${PBPPO_QEMU_AARCH64};-L;${PBPPO_ARM64_ROOT}")
endif()

# GCC's note that aarch64 passes std::pair differently from GCC < 10.1 in C++17 (Simbody's headers
# print it hundreds of times): every library here is built by GCC 12, so it concerns none.
set(CMAKE_CXX_FLAGS_INIT "-Wno-psabi")

# Open MPI's compiler wrappers (mpicc), which FindMPI asks for flags, are the machine's own and
# speak for its x86-64 installation: FindMPI is given the root's MPI instead (libopenmpi-dev).
set(pbppo_mpi "${PBPPO_ARM64_ROOT}/usr/lib/aarch64-linux-gnu/openmpi")
if(EXISTS "${pbppo_mpi}/include/mpi.h")
  set(MPI_C_COMPILER "MPI_C_COMPILER-NOTFOUND")
  set(MPI_C_HEADER_DIR "${pbppo_mpi}/include")
  set(MPI_C_LIB_NAMES mpi)
  set(MPI_mpi_LIBRARY "${pbppo_mpi}/lib/libmpi.so")
endif()
