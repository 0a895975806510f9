#pragma once
// Subnormal numbers (magnitudes below 2.2e-308) cost x86 cores a microcode assist of about a
// hundred cycles for each operation that reads or makes one. A packing makes many: generating a
// 10,253-grain Brenna cylinder took 193 s with them and 8.8 s with them flushed to zero, to a
// byte-identical sample (bench/RESULTS.md, "Subnormals flushed to zero"). No quantity of the
// physics lives near 1e-308 (a metre, a newton, a joule), so flushing them changes no result a
// test or a user can see; it makes the cost of a step independent of how still its grains are.
namespace breccia {

// The calling thread's floating-point mode (x86-64: MXCSR; AArch64: FPCR).
using FloatMode = unsigned long;

// Flushes subnormal results to zero and reads subnormal operands as zero in the calling thread
// (x86-64: MXCSR's FTZ and DAZ bits; AArch64: FPCR.FZ; elsewhere nothing). Threads started
// afterwards inherit the mode (POSIX: a new thread starts with its creator's floating-point
// environment), so a program sets it first thing in main(), before OpenMP starts its threads.
// Returns the mode before.
FloatMode flush_subnormals() noexcept;

// Restores a mode that flush_subnormals returned.
void restore_float_mode(FloatMode mode) noexcept;

// True when the calling thread flushes subnormals (false where the platform has no such mode).
bool subnormals_flushed() noexcept;

// Flushes subnormals in the calling thread for the object's lifetime: for the engine's entry
// points in a process it does not own (the Python module), whose other code keeps its mode.
class SubnormalsFlushed {
 public:
  SubnormalsFlushed() noexcept : saved_(flush_subnormals()) {}
  ~SubnormalsFlushed() { restore_float_mode(saved_); }
  SubnormalsFlushed(const SubnormalsFlushed&) = delete;
  SubnormalsFlushed& operator=(const SubnormalsFlushed&) = delete;

 private:
  FloatMode saved_;
};

}  // namespace breccia
