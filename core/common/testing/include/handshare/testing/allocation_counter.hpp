#pragma once
/// Counts heap allocations in a test binary that links handshare::allocation_counter (it
/// replaces the global operator new and delete), so a test can assert that a real-time step
/// allocates nothing.
namespace handshare::testing {
long AllocationCount() noexcept;
}  // namespace handshare::testing
