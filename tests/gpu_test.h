#pragma once
// The validation helper: every GPU test derives from GpuTest, which creates the device with
// VK_LAYER_KHRONOS_validation *and* synchronization validation (a missing layer fails the test,
// never skips it) and fails the test if the layer reported any warning or error. Opting out is
// not possible; a test that expects messages (validation_test.cpp) must take them with
// takeMessages() and check them itself.
#include <gtest/gtest.h>

#include <mutex>
#include <string>
#include <vector>

#include "engine/device.h"
#include "tools/own_device.h"

namespace canopy::test {

struct ValidationMessage {
  std::string id;
  std::string text;
  bool error = false;
};

class GpuTest : public ::testing::Test {
 protected:
  void SetUp() override;
  // Lets a fixture change the device description (e.g. hide a feature) before creation.
  virtual void configure(DeviceDesc&) {}
  void TearDown() override;
  // Removes and returns the messages captured so far.
  std::vector<ValidationMessage> takeMessages();
  // Waits for the queue so that messages from submitted work have arrived.
  void waitIdle();

  Device dev;
  std::mutex mutex_;
  std::vector<ValidationMessage> messages_;
};

// Formats messages for a failure report.
std::string describe(const std::vector<ValidationMessage>& messages);

}  // namespace canopy::test
