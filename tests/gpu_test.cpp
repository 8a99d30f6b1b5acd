#include "tests/gpu_test.h"
#include "tools/own_device.h"

#include <cstdlib>

namespace canopy::test {

void GpuTest::SetUp() {
  DeviceDesc desc;
  desc.applicationName = "canopy-tests";
  desc.enableValidation = true;
  desc.requireValidation = true;
  desc.enableSyncValidation = true;
  desc.validationSink = [this](VkDebugUtilsMessageSeverityFlagBitsEXT sev, const char* id, const char* msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    messages_.push_back({id, msg, sev >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT});
  };
  configure(desc);
  Status s = createDevice(desc, &dev);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_TRUE(dev.validationEnabled);
}

void GpuTest::TearDown() {
  destroyDevice(dev);
  std::lock_guard<std::mutex> lock(mutex_);
  EXPECT_TRUE(messages_.empty()) << "validation reported " << messages_.size() << " message(s):\n"
                                 << describe(messages_);
}

std::vector<ValidationMessage> GpuTest::takeMessages() {
  waitIdle();
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<ValidationMessage> out;
  out.swap(messages_);
  return out;
}

void GpuTest::waitIdle() {
  if (dev.device) vkQueueWaitIdle(dev.queue);  // the test's own queue: its submitted work has reported
}

std::string describe(const std::vector<ValidationMessage>& messages) {
  std::string s;
  for (const auto& m : messages) s += (m.error ? "  [error] " : "  [warning] ") + m.id + ": " + m.text + "\n";
  return s;
}

}  // namespace canopy::test

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
