#include "breccia/core/float_mode.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif

namespace breccia {

namespace {

#if defined(__x86_64__) || defined(__i386__)
constexpr unsigned kFlushToZero = 0x8000;       // MXCSR.FTZ: subnormal results become zero
constexpr unsigned kDenormalsAreZero = 0x0040;  // MXCSR.DAZ: subnormal operands read as zero
constexpr FloatMode kFlush = kFlushToZero | kDenormalsAreZero;
FloatMode read_mode() noexcept {
  return _mm_getcsr();
}
void write_mode(FloatMode m) noexcept {
  _mm_setcsr(static_cast<unsigned>(m));
}
#elif defined(__aarch64__)
constexpr FloatMode kFlush = FloatMode{1} << 24;  // FPCR.FZ
FloatMode read_mode() noexcept {
  FloatMode m;
  asm volatile("mrs %0, fpcr" : "=r"(m));
  return m;
}
void write_mode(FloatMode m) noexcept {
  asm volatile("msr fpcr, %0" : : "r"(m));
}
#else
constexpr FloatMode kFlush = 0;
FloatMode read_mode() noexcept {
  return 0;
}
void write_mode(FloatMode) noexcept {}
#endif

}  // namespace

FloatMode flush_subnormals() noexcept {
  const FloatMode before = read_mode();
  write_mode(before | kFlush);
  return before;
}

void restore_float_mode(FloatMode mode) noexcept {
  write_mode(mode);
}

bool subnormals_flushed() noexcept {
  return kFlush != 0 && (read_mode() & kFlush) == kFlush;
}

}  // namespace breccia
