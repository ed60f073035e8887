#pragma once
/// Counts heap allocations in the test binary that links allocation_counter.cpp (it replaces
/// the global operator new), so a test can assert that a real-time step allocates nothing.
namespace handshare::test {
long AllocationCount() noexcept;
}  // namespace handshare::test
