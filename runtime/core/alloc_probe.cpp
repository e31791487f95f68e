#include "runtime/core/alloc_probe.hpp"

#include <cstddef>
#include <cstdlib>
#include <new>

namespace {
thread_local bool t_counting = false;
thread_local std::uint64_t t_count = 0;
inline void Note() noexcept {
  if (t_counting) ++t_count;
}
}  // namespace

#if defined(PBPPO_SANITIZED)
// Sanitizers own malloc; they call these hooks on every allocation, operator new included.
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*, std::size_t),
                                                         void (*free_hook)(const volatile void*));
namespace {
void OnMalloc(const volatile void*, std::size_t) {
  Note();
}
void OnFree(const volatile void*) {}
const bool g_hooks_installed = __sanitizer_install_malloc_and_free_hooks(OnMalloc, OnFree) != 0;
}  // namespace
bool pbppo::AllocationCountingActive() noexcept {
  return g_hooks_installed;
}
#else
// glibc: replace the allocation functions, forwarding to glibc's own implementations.
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) {
  Note();
  return __libc_malloc(n);
}
void* calloc(std::size_t a, std::size_t b) {
  Note();
  return __libc_calloc(a, b);
}
void* realloc(void* p, std::size_t n) {
  Note();
  return __libc_realloc(p, n);
}
void* aligned_alloc(std::size_t align, std::size_t n) {
  Note();
  return __libc_memalign(align, n);
}
void* memalign(std::size_t align, std::size_t n) {
  Note();
  return __libc_memalign(align, n);
}
int posix_memalign(void** out, std::size_t align, std::size_t n) {
  Note();
  void* p = __libc_memalign(align, n);
  if (p == nullptr) return 12;  // ENOMEM
  *out = p;
  return 0;
}
void free(void* p) {
  __libc_free(p);
}
}
bool pbppo::AllocationCountingActive() noexcept {
  return true;
}
#endif

namespace pbppo {
AllocationScope::AllocationScope() noexcept : start_(t_count) {
  t_counting = true;
}
AllocationScope::~AllocationScope() {
  t_counting = false;
}
std::uint64_t AllocationScope::count() const noexcept {
  return t_count - start_;
}
}  // namespace pbppo
