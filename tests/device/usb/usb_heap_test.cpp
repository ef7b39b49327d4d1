// UsbHeapTest: what the heap sees per servo tick on the `usb` plugin, counted by the malloc
// interposer (malloc_count.hpp) on the ticking thread. Our own code allocates nothing (the
// AllocationGuard of usb_device_test proves that for operator new); this measures what libusb
// does below it, for docs/transport-usb.md ("Allocation"): its Linux backend calloc()s the URB
// of every submitted transfer (linux_usbfs.c, submit_bulk_transfer) and frees it when the
// transfer is reaped. ASan and TSan own malloc and refuse an interposer; under them the
// sanitizers' hooks (alloc_guard.hpp) count the same calls, without telling calloc from malloc.
#include <gtest/gtest.h>
#include <libusb.h>

#include <cstddef>
#include <cstdint>
#include <iostream>

#include "alloc_guard.hpp"
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/usb/make_usb_link.hpp"
#include "malloc_count.hpp"
#include "usb_testbed.hpp"

namespace hapticd::device::usb {
namespace {

TEST(UsbHeapTest, LibusbCallocsOneUrbPerSubmittedTransfer) {
    testing::UsbTestbed testbed;
    testing::UsbDeviceSpec spec;
    spec.emulator = testing::pen_display_emulator("EMU-0001");
    testbed.add(spec);
    link::ProtocolDevice device("usb", make_usb_link);
    DeviceConfig config;
    config.lockstep = true;
    config.plugin_table_toml = "serial_number = \"EMU-0001\"\n";
    device.open(config);

    auto tick = [&device] {
        Sample sample;
        Command command;
        command.force_n[0] = 0.5;
        command.enable = true;
        return device.read(sample) == IoResult::ok && device.write(command) == IoResult::ok;
    };
    for (int i = 0; i < 10; ++i) ASSERT_TRUE(tick());  // the first read polls: one more OUT

    constexpr int kTicks = 2000;
    int ok = 0;
#if HAPTICD_ALLOC_GUARD_HOOKS
    std::uint64_t allocations = 0;
    std::uint64_t frees = 0;
    {
        hapticd::testing::AllocationGuard guard;
        for (int i = 0; i < kTicks; ++i) ok += tick() ? 1 : 0;
        allocations = guard.allocations();
        frees = guard.deallocations();
    }
    device.close();
    ASSERT_EQ(ok, kTicks);
    // One OUT and one IN transfer a tick, one calloc each (below), and nothing else.
    EXPECT_EQ(allocations, 2u * kTicks);
    EXPECT_EQ(frees, 2u * kTicks);
#else
    const hapticd::testing::HeapCalls before = hapticd::testing::thread_heap_calls();
    for (int i = 0; i < kTicks; ++i) ok += tick() ? 1 : 0;
    const hapticd::testing::HeapCalls counts = hapticd::testing::thread_heap_calls() - before;
    device.close();
    ASSERT_EQ(ok, kTicks);

    std::cout << "[usb] heap calls per tick on the servo thread (libusb "
              << "1.0." << libusb_get_version()->micro << "): malloc "
              << static_cast<double>(counts.malloc) / kTicks << ", calloc "
              << static_cast<double>(counts.calloc) / kTicks << ", realloc "
              << static_cast<double>(counts.realloc) / kTicks << ", free "
              << static_cast<double>(counts.free) / kTicks << "\n";
    // Per tick one OUT transfer (the command) and one IN transfer (resubmitted after the
    // sample) are submitted: one calloc each, freed when reaped. Nothing else.
    EXPECT_EQ(counts.calloc, 2u * kTicks);
    EXPECT_EQ(counts.malloc, 0u);
    EXPECT_EQ(counts.realloc, 0u);
    EXPECT_EQ(counts.free, 2u * kTicks);
#endif
}

}  // namespace
}  // namespace hapticd::device::usb
