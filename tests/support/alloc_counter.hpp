#pragma once
// Counts global operator new calls in a test binary that links inhand_alloc_counter, for
// "allocates nothing after warm-up" tests.
namespace inhand::test {
long AllocationCount();
}
