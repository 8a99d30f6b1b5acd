// canopy-demo: the method on a whole scene. Headless (default): renders --frames frames of the
// animated scene, writes frame_NNNN.png, contact_sheet.png, timing.txt (and demo.mp4 when ffmpeg
// is installed) into --out. --window: a live window (demo/demo_window.cpp).
//
// Exit 0 on success, 1 on a failure (including any validation message with --validate), 2 on a
// bad option (one line naming it and its allowed values).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <unistd.h>

#include "demo/demo_app.h"
#include "engine/image_io.h"

using namespace canopy;
using namespace canopy::demo;

namespace canopy::demo {
// demo_window.cpp: 0/1 = done; -1 = no display (the caller falls back to headless).
int runWindow(const Options& o, const VegetationModel& model, const std::string& label);
}

namespace {

double nowMs() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Up to 12 frames spread over the sequence, 4 per row, each shrunk by an integer factor to at most
// 240 pixels wide (box filter), with a 4-pixel white gutter.
Status writeContactSheet(const std::string& path, const std::vector<std::vector<uint8_t>>& frames, uint32_t w, uint32_t h,
                         std::vector<size_t>* picked) {
  const size_t count = std::min<size_t>(12, frames.size());
  picked->clear();
  for (size_t i = 0; i < count; ++i) picked->push_back(count == 1 ? 0 : i * (frames.size() - 1) / (count - 1));
  const uint32_t f = std::max(1u, (w + 239) / 240), tw = w / f, th = h / f, gap = 4;
  const uint32_t cols = uint32_t(std::min<size_t>(4, count)), rows = uint32_t((count + cols - 1) / cols);
  const uint32_t W = cols * tw + (cols + 1) * gap, H = rows * th + (rows + 1) * gap;
  std::vector<uint8_t> sheet(size_t(W) * H * 4, 255);
  for (size_t k = 0; k < count; ++k) {
    const std::vector<uint8_t>& src = frames[(*picked)[k]];
    const uint32_t ox = gap + uint32_t(k % cols) * (tw + gap), oy = gap + uint32_t(k / cols) * (th + gap);
    for (uint32_t y = 0; y < th; ++y)
      for (uint32_t x = 0; x < tw; ++x)
        for (int c = 0; c < 4; ++c) {
          uint32_t sum = 0;
          for (uint32_t j = 0; j < f; ++j)
            for (uint32_t i = 0; i < f; ++i) sum += src[((size_t(y) * f + j) * w + x * f + i) * 4 + c];
          sheet[((size_t(oy) + y) * W + ox + x) * 4 + c] = uint8_t(sum / (f * f));
        }
  }
  return writePng(path, W, H, sheet);
}

int runHeadless(const Options& o, const VegetationModel& model, const std::string& label) {
  DeviceDesc dd;
  dd.applicationName = "canopy-demo";
  dd.preferredDevice = o.device;
  int messages = 0;
  if (o.validate) {
    dd.enableValidation = dd.requireValidation = true;
    dd.validationSink = [&](VkDebugUtilsMessageSeverityFlagBitsEXT, const char* id, const char* text) {
      ++messages;
      std::fprintf(stderr, "validation: %s: %s\n", id ? id : "", text);
    };
  }
  Device dev;
  Status s = createDevice(dd, &dev);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-demo: %s\n", s.message().c_str());
    return 1;
  }
  Host host;
  s = [&]() -> Status {
    std::error_code ec;
    std::filesystem::create_directories(o.outDir, ec);
    if (ec) return Status::error("cannot create the output folder '" + o.outDir + "': " + ec.message());
    CANOPY_TRY(createHost(dev, model, o, o.width, o.height, true, VK_FORMAT_UNDEFINED, &host));
    const CameraRig rig0 = defaultRig(o);
    TimingLog first, steady;
    std::vector<std::vector<uint8_t>> frames;
    const double t0 = nowMs();
    for (uint32_t i = 0; i < o.frames; ++i) {
      CameraRig rig = rig0;
      if (o.camera == CameraPath::Orbit && o.frames > 1) rig.yaw += o.orbitDegrees * float(i) / float(o.frames - 1);
      CanopyFrame f;
      f.camera = cameraView(rig, model, o.width, o.height);
      f.dt = 1.0f / o.fps;
      const double w0 = nowMs();
      CANOPY_TRY(submitAndWait(dev, [&](VkCommandBuffer cmd) { return recordHostFrame(host, cmd, f, nullptr); }));
      const double wall = nowMs() - w0;
      std::vector<PassTiming> t;
      CANOPY_TRY(host.timer.read(dev, &t));
      // The first frame slices the layers (and every orbit frame re-slices): kept apart from the steady state.
      (i == 0 ? first : steady).add(t, wall);
      std::vector<uint8_t> rgba;
      readPixels(host, &rgba);
      char name[64];
      std::snprintf(name, sizeof name, "/frame_%04u.png", i);
      CANOPY_TRY(writePng(o.outDir + name, o.width, o.height, rgba));
      frames.push_back(std::move(rgba));
      std::fprintf(stderr, "%sframe %u / %u (%.1f frames/s)%s", isatty(2) ? "\r" : "", i + 1, o.frames,
                   double(i + 1) * 1000.0 / std::max(nowMs() - t0, 1e-3), isatty(2) && i + 1 < o.frames ? "" : "\n");
    }
    std::vector<size_t> picked;
    CANOPY_TRY(writeContactSheet(o.outDir + "/contact_sheet.png", frames, o.width, o.height, &picked));
    const CanopyStats st = canopyStats(host.canopy);
    char head[2048];
    std::snprintf(head, sizeof head,
                  "canopy-demo: %s, %ux%u, layers %s, %s delay, wind %.2f units/s at %.2f Hz, %u frames at dt = 1/%g s, "
                  "camera %s\ndevice: %s; %u layer re-slices\n"
                  "On a CPU driver (lavapipe) timestamps around compute passes read near zero once anything was drawn "
                  "(design.md): the wall-clock line is the figure to trust there.\n",
                  label.c_str(), o.width, o.height, o.layout.c_str(), o.delay == DelayMode::Exact ? "exact" : "approximate",
                  o.windStrength, o.windFrequency, o.frames, o.fps, o.camera == CameraPath::Orbit ? "orbit" : "still",
                  dev.properties.deviceName, uint32_t(st.layers.rebuilds));
    std::string text = head;
    text += first.summary("\nFirst frame (slices the layers):");
    if (!steady.wallMs.empty())
      text += steady.summary("\nFrames 2.." + std::to_string(o.frames) + " (medians" +
                             (o.camera == CameraPath::Orbit ? std::string(", every frame re-slices") : std::string()) + "):");
    if (FILE* f = std::fopen((o.outDir + "/timing.txt").c_str(), "w")) {
      std::fputs(text.c_str(), f);
      std::fclose(f);
    }
    std::printf("%s\n", text.c_str());
    std::printf("wrote %u frames (%s/frame_0000.png ...), %s/contact_sheet.png (frames", o.frames, o.outDir.c_str(),
                o.outDir.c_str());
    for (size_t k : picked) std::printf(" %zu", k);
    std::printf("), %s/timing.txt\n", o.outDir.c_str());
    if (o.mp4 && std::system("command -v ffmpeg >/dev/null 2>&1") == 0) {
      const std::string cmd = "ffmpeg -y -loglevel error -framerate " + std::to_string(int(std::lround(o.fps))) + " -i '" +
                              o.outDir + "/frame_%04d.png' -vf 'scale=trunc(iw/2)*2:trunc(ih/2)*2' -pix_fmt yuv420p '" +
                              o.outDir + "/demo.mp4'";
      if (std::system(cmd.c_str()) == 0) std::printf("wrote %s/demo.mp4\n", o.outDir.c_str());
      else std::fprintf(stderr, "canopy-demo: ffmpeg failed; the PNG frames are complete\n");
    } else if (o.mp4) {
      std::printf("(no demo.mp4: ffmpeg is not installed)\n");
    }
    return Status();
  }();
  if (!s.ok()) std::fprintf(stderr, "canopy-demo: %s\n", s.message().c_str());
  destroyHost(host);
  destroyDevice(dev);
  if (messages > 0) {
    std::fprintf(stderr, "canopy-demo: %d validation messages\n", messages);
    return 1;
  }
  return s.ok() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  std::string err;
  const int rc = parseOptions(argc, argv, &o, &err);
  if (rc == 1) return 0;
  if (rc == 2) {
    std::fprintf(stderr, "canopy-demo: %s\n", err.c_str());
    return 2;
  }
  VegetationModel model;
  std::string label;
  const Status s = loadScene(o, &model, &label);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-demo: %s\n", s.message().c_str());
    return 1;
  }
  if (o.window) {
    const int w = runWindow(o, model, label);
    if (w >= 0) return w;
    // No display: runWindow said why; the headless run writes the files instead.
    if (o.frames == 0) o.frames = Options().frames;
  }
  return runHeadless(o, model, label);
}
