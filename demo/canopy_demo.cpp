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
#include <cerrno>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

#include "demo/cli.h"
#include "demo/demo_app.h"
#include "demo/foliage_folders.h"
#include "demo/frame_writer.h"
#include "tools/fault_loader.h"
#include "tools/image_io.h"
#include "tools/world_lock.h"

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

// Whether an RGBA8 pixel differs from the clear colour (sRGB bytes): something was drawn there.
bool drawn(const uint8_t* p, const uint8_t clear[3]) {
  return std::abs(int(p[0]) - clear[0]) + std::abs(int(p[1]) - clear[1]) + std::abs(int(p[2]) - clear[2]) > 24;
}

// Up to 12 frames spread over the sequence (which ones depends only on the count, so only those
// are kept in memory while rendering).
std::vector<size_t> contactSheetFrames(size_t frameCount) {
  const size_t count = std::min<size_t>(12, frameCount);
  std::vector<size_t> picked;
  for (size_t i = 0; i < count; ++i) picked.push_back(count == 1 ? 0 : i * (frameCount - 1) / (count - 1));
  return picked;
}

// The picked frames, 4 per row, with a 4-pixel white gutter. All are cropped to one box, the
// union of where anything differs from the clear colour in any of them plus a margin, so the
// vegetation fills the sheet and its motion between frames is comparable; each crop is shrunk by
// an integer factor (box filter) to at most 240 pixels wide. *crop receives the box (x0, y0, x1, y1).
Status writeContactSheet(const std::string& path, const std::vector<std::vector<uint8_t>>& frames, uint32_t w, uint32_t h,
                         const uint8_t clear[3], glm::uvec4* crop) {
  const size_t count = frames.size();
  uint32_t x0 = w, y0 = h, x1 = 0, y1 = 0;
  for (const std::vector<uint8_t>& f : frames)
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        if (drawn(&f[(size_t(y) * w + x) * 4], clear))
          x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
      }
  if (x0 >= x1 || y0 >= y1) x0 = y0 = 0, x1 = w, y1 = h;  // nothing drawn: the whole frame
  const uint32_t mx = w / 25, my = h / 25;
  x0 = x0 > mx ? x0 - mx : 0, y0 = y0 > my ? y0 - my : 0, x1 = std::min(w, x1 + mx), y1 = std::min(h, y1 + my);
  *crop = glm::uvec4(x0, y0, x1, y1);
  const uint32_t cw = x1 - x0, ch = y1 - y0;
  const uint32_t f = std::max(1u, (cw + 239) / 240), tw = std::max(1u, cw / f), th = std::max(1u, ch / f), gap = 4;
  const uint32_t cols = uint32_t(std::min<size_t>(4, count)), rows = uint32_t((count + cols - 1) / cols);
  const uint32_t W = cols * tw + (cols + 1) * gap, H = rows * th + (rows + 1) * gap;
  std::vector<uint8_t> sheet(size_t(W) * H * 4, 255);
  for (size_t k = 0; k < count; ++k) {
    const std::vector<uint8_t>& src = frames[k];
    const uint32_t ox = gap + uint32_t(k % cols) * (tw + gap), oy = gap + uint32_t(k / cols) * (th + gap);
    for (uint32_t y = 0; y < th; ++y)
      for (uint32_t x = 0; x < tw; ++x)
        for (int c = 0; c < 4; ++c) {
          uint32_t sum = 0, n = 0;
          for (uint32_t j = 0; j < f; ++j)
            for (uint32_t i = 0; i < f; ++i) {
              const uint32_t sx = x0 + x * f + i, sy = y0 + y * f + j;
              if (sx < x1 && sy < y1) sum += src[(size_t(sy) * w + sx) * 4 + c], ++n;
            }
          sheet[((size_t(oy) + y) * W + ox + x) * 4 + c] = uint8_t(n ? sum / n : 255);
        }
  }
  return writePng(path, W, H, sheet);
}

// How much the vegetation sways in the written frames, measured on the pixels themselves (still
// camera): the vegetation is every pixel that differs from the clear colour; the rows of the top
// third of frame 0's silhouette are followed, and the horizontal centroid of the vegetation in
// those rows is recorded per frame. Its range is the sway of the crown in pixels.
struct SwayMeter {
  uint8_t clear[3] = {0, 0, 0};
  uint32_t width = 0, height = 0, rowBegin = 0, rowEnd = 0;
  bool greyGround = false;  // --shadows: the ground is grey at every shade (never vegetation)
  std::vector<double> centroidX;

  bool vegetation(const uint8_t* p) const {
    const bool grey = std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]}) <= 4;
    return drawn(p, clear) && !(greyGround && grey);
  }
  void add(const std::vector<uint8_t>& rgba) {
    if (centroidX.empty()) {  // the rows to follow, from frame 0
      uint32_t top = height, bottom = 0;
      for (uint32_t y = 0; y < height; ++y)
        for (uint32_t x = 0; x < width; ++x)
          if (vegetation(&rgba[(size_t(y) * width + x) * 4])) {
            top = std::min(top, y);
            bottom = std::max(bottom, y);
          }
      rowBegin = top;
      rowEnd = top < bottom ? top + (bottom - top + 1) / 3 : top;
    }
    double sum = 0, count = 0;
    for (uint32_t y = rowBegin; y < rowEnd; ++y)
      for (uint32_t x = 0; x < width; ++x)
        if (vegetation(&rgba[(size_t(y) * width + x) * 4])) {
          sum += x;
          count += 1;
        }
    centroidX.push_back(count > 0 ? sum / count : 0.0);
  }
  std::string summary() const {
    if (centroidX.size() < 2 || rowEnd <= rowBegin) return "";
    const auto lo = std::min_element(centroidX.begin(), centroidX.end());
    const auto hi = std::max_element(centroidX.begin(), centroidX.end());
    char line[256];
    std::snprintf(line, sizeof line,
                  "Sway (top third of the vegetation, rows %u..%u): horizontal centroid %.1f .. %.1f px, range %.1f px "
                  "(frames %zu and %zu)\n",
                  rowBegin, rowEnd - 1, *lo, *hi, *hi - *lo, size_t(lo - centroidX.begin()), size_t(hi - centroidX.begin()));
    return line;
  }
};

// --shadows: the caster's centroid in the shadow map along the direction the camera's right runs
// there (light pixels), per written frame, against the crown's on-screen centroid (SwayMeter).
struct ShadowMeter {
  glm::vec2 axis{1.0f, 0.0f};  // unit, in the map's pixels
  std::vector<double> centroid;
  void add(const std::vector<float>& depth, uint32_t size) {
    double sum = 0, n = 0;
    for (uint32_t y = 0; y < size; ++y)
      for (uint32_t x = 0; x < size; ++x)
        if (depth[size_t(y) * size + x] < 1.0f) {
          sum += glm::dot(glm::vec2(x + 0.5f, y + 0.5f), axis);
          n += 1;
        }
    centroid.push_back(n > 0 ? sum / n : 0.0);
  }
  static double sd(const std::vector<double>& v) {
    double m = 0, q = 0;
    for (double x : v) m += x / double(v.size());
    for (double x : v) q += (x - m) * (x - m) / double(v.size());
    return std::sqrt(q);
  }
  std::string summary(const std::vector<double>& screen) const {
    const size_t n = std::min(screen.size(), centroid.size());
    if (n < 2) return "";
    double ma = 0, mb = 0, ab = 0, aa = 0, bb = 0;
    for (size_t i = 0; i < n; ++i) ma += screen[i] / double(n), mb += centroid[i] / double(n);
    for (size_t i = 0; i < n; ++i) {
      ab += (screen[i] - ma) * (centroid[i] - mb);
      aa += (screen[i] - ma) * (screen[i] - ma);
      bb += (centroid[i] - mb) * (centroid[i] - mb);
    }
    char line[320];
    std::snprintf(line, sizeof line,
                  "Shadow (recordCanopyShadow, every frame): the caster's centroid in the map sways %.3f light px (s.d.) along "
                  "the camera's right, the crown's on screen %.3f px; correlation %.3f over %zu frames\n",
                  sd(centroid), sd(screen), aa > 0 && bb > 0 ? ab / std::sqrt(aa * bb) : 0.0, n);
    return line;
  }
};

constexpr int kNotInstalled = 127;

// Runs a program found on PATH with these arguments and waits: its exit code, kNotInstalled when
// it cannot be started, 128 + signal when a signal ended it.
int runProgram(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return kNotInstalled;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return kNotInstalled;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : 1;
}

// The device for a headless run: validation (each message counted in *messages and printed) and
// the fault-injecting loader as the options ask.
Status createDemoDevice(const Options& o, int* messages, Device* dev) {
  DeviceDesc dd;
  dd.applicationName = "canopy-demo";
  dd.preferredDevice = o.device;
  if (o.validate) {
    dd.enableValidation = dd.requireValidation = true;
    dd.validationSink = [messages](VkDebugUtilsMessageSeverityFlagBitsEXT, const char* id, const char* text) {
      ++*messages;
      std::fprintf(stderr, "validation: %s: %s\n", id ? id : "", text);
    };
  }
  if (!o.injectFault.empty()) {
    fault::Mode mode = fault::Mode::Off;
    int64_t n = 0;
    fault::parse(o.injectFault, &mode, &n);  // checked by parseOptions
    fault::arm(mode, n);
    dd.getInstanceProcAddr = fault::loader(vkGetInstanceProcAddr);
  }
  return createDevice(dd, dev);
}

// timing.txt: the run's settings and re-slices, the first and the steady frames' timings, the sway
// (still camera), memory.
// Frames measured alone after the sequence (Canopy's frame with no PNG written beside it).
constexpr uint32_t kHeldFrames = 10;

std::string timingReport(const Options& o, const std::string& label, const Device& dev, const CanopyStats& st,
                         uint32_t warmup, const TimingLog& first, const TimingLog& steady, const TimingLog& alone,
                         const std::vector<double>& pngMs, const SwayMeter* sway, const ShadowMeter* shadow = nullptr) {
  char head[2048];
  std::snprintf(head, sizeof head,
                "canopy-demo: %s, %ux%u, layers %s, %s delay, wind %s, "
                "%.2f s warm-up, %u frames at dt = 1/%g s, camera %s\ndevice: %s; %u layer re-slices (%u spread over frames "
                "with a %.1f ms budget, the last over %u frames, largest slice %llu triangles; %u at once for a moving "
                "camera a spread one would fall behind; the last for: %s)\n"
                "On a CPU driver (lavapipe) timestamps around compute passes read near zero once anything was drawn "
                "(docs/design.md): the wall-clock line is the figure to trust there.\n",
                label.c_str(), o.width, o.height, o.layout.c_str(), o.delay == DelayMode::Exact ? "exact" : "approximate",
                windText(o).c_str(), double(warmup) / o.fps, o.frames, o.fps, cameraMotionName(o.camera),
                dev.properties.deviceName, uint32_t(st.layers.rebuilds), uint32_t(st.layers.spreadRebuilds), o.rebuildBudgetMs,
                st.layers.lastSpreadFrames, (unsigned long long)st.layers.maxSliceTriangles, uint32_t(st.layers.outrunSpreads),
                st.layers.lastRebuildReason.c_str());
  std::string text = head;
  if (st.layers.species > 1 || st.layers.instances > 1) {
    char copies[256];
    std::snprintf(copies, sizeof copies, "species: %u, copies: %u; in the last re-slice's view: %u copies of %u species\n",
                  st.layers.species, st.layers.instances, st.layers.lastVisibleInstances,
                  st.layers.lastVisibleSpecies);
    text += copies;
  }
  if (st.layers.impostorBakedBoxes > 0) {
    char imp[256];
    std::snprintf(imp, sizeof imp, "impostors: %u boxes baked; the last re-slice drew %u as impostors (%u fading) for %u copies, and %llu foliage triangles\n",
                  st.layers.impostorBakedBoxes, st.layers.lastImpostors, st.layers.lastFadingBoxes, st.layers.lastImpostorCopies,
                  (unsigned long long)st.layers.lastDrawnTriangles);
    text += imp;
  }
  text += first.summary(warmup > 0 ? "\nFirst frame (of the warm-up; slices the layers):" : "\nFirst frame (slices the layers):");
  if (!steady.wallMs.empty())
    text += steady.summary((warmup > 0 ? "\nWritten frames 1.." : "\nFrames 2..") + std::to_string(o.frames) + " (medians" +
                           (o.reslice == ReslicePolicy::EveryFrame ? std::string(", every frame re-slices")
                            : o.camera != CameraMotion::Still
                                ? std::string(o.rebuildBudgetMs > 0 ? ", re-slices spread over frames" : ", re-slices at once")
                                : std::string()) + "):");
  if (!pngMs.empty()) {
    std::vector<double> v = pngMs;
    std::sort(v.begin(), v.end());
    char line[256];
    std::snprintf(line, sizeof line,
                  "  %-40s %10.3f %10.3f\n  (the demo's own work, on a worker thread; on a CPU driver it shares the cores with "
                  "the frames above)\n",
                  "PNG file per frame (encode + write)", v[v.size() / 2], v.back());
    text += line;
  }
  if (!alone.wallMs.empty()) {
    std::vector<double> v = alone.wallMs;
    std::sort(v.begin(), v.end());
    char line[256];
    std::snprintf(line, sizeof line,
                  "Canopy's frame alone (the last view held, %u frames one at a time, submit to fence, no file written):\n"
                  "  %-40s %10.3f %10.3f   (%.1f FPS)\n",
                  kHeldFrames, "whole frame, wall clock", v[v.size() / 2], v.back(), 1000.0 / std::max(v[v.size() / 2], 1e-6));
    text += line;
  }
  if (sway) text += "\n" + sway->summary();
  if (sway && shadow) text += shadow->summary(sway->centroidX);
  char ringNote[128];
  std::snprintf(ringNote, sizeof ringNote, st.layers.meshResident ? "resident" : "streamed through a %.1f MiB ring",
                double(st.layers.meshRingBytes) / double(1 << 20));
  char mem[640];
  std::snprintf(mem, sizeof mem,
                "\nMemory: peak host %.2f GiB (VmHWM; on a CPU driver it includes device memory), device %.1f MiB live / "
                "%.1f MiB peak (Canopy's buffers and images), mesh %.1f MiB in %u chunks (%.1f bytes per face), %s\n",
                double(cli::peakResidentBytes()) / double(1ull << 30), double(st.deviceBytes) / double(1 << 20),
                double(st.peakDeviceBytes) / double(1 << 20), double(st.layers.meshBytes) / double(1 << 20),
                st.layers.meshChunks,
                double(st.layers.meshBytes) / double(std::max<uint64_t>(st.layers.foliageTriangles + st.layers.rigidTriangles, 1)),
                ringNote);
  text += mem;
  return text;
}

// demo.mp4 from the written frames. ffmpeg gets its arguments directly (no shell), so an output
// folder with quotes or spaces cannot break or inject into the command.
void writeMp4(const Options& o) {
  const std::string fps = std::to_string(std::max(1l, std::lround(o.fps)));
  const int rc = runProgram({"ffmpeg", "-y", "-loglevel", "error", "-framerate", fps, "-i", o.outDir + "/frame_%04d.png",
                             "-frames:v", std::to_string(o.frames),
                             "-vf", "scale=trunc(iw/2)*2:trunc(ih/2)*2", "-pix_fmt", "yuv420p", o.outDir + "/demo.mp4"});
  if (rc == 0) std::printf("wrote %s/demo.mp4\n", o.outDir.c_str());
  else if (rc == kNotInstalled) std::printf("(no demo.mp4: ffmpeg is not installed)\n");
  else std::fprintf(stderr, "canopy-demo: ffmpeg failed (exit %d); the PNG frames are complete\n", rc);
}

// The output folder, created; frames beyond this run's count left by a longer earlier run in the
// same folder would read as part of this sequence (and of the MP4): they go.
Status prepareOutputFolder(const Options& o) {
  std::error_code ec;
  std::filesystem::create_directories(o.outDir, ec);
  if (ec) return Status::error("cannot create the output folder '" + o.outDir + "': " + ec.message());
  for (uint32_t i = o.frames;; ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "/frame_%04u.png", i);
    if (!std::filesystem::remove(o.outDir + name, ec)) break;
  }
  return Status();
}

void printWrittenFiles(const Options& o, const std::vector<size_t>& picked, const glm::uvec4& crop) {
  std::printf("wrote %u frames (%s/frame_0000.png ...), %s/contact_sheet.png (frames", o.frames, o.outDir.c_str(),
              o.outDir.c_str());
  for (size_t k : picked) std::printf(" %zu", k);
  std::printf(", cropped to x %u..%u, y %u..%u), %s/timing.txt\n", crop.x, crop.z - 1, crop.y, crop.w - 1, o.outDir.c_str());
}

using SubmitFrame = std::function<Status(CanopyFrame, bool, int64_t)>;
using WrittenFrame = std::function<Status(uint32_t, const std::vector<uint8_t>&)>;

// A mesh over the device-memory budget is streamed: its first re-slice takes a slice a frame
// (CanopyDesc.deviceMemoryBudget). More unwritten frames of `frame` until the layers are complete,
// so the first written frame shows the whole plant.
Status completeStreamedReslice(Host& host, uint32_t warmup, const CanopyFrame& frame, const SubmitFrame& submit,
                               const std::function<Status()>& drain) {
  if (warmup == 0) CANOPY_TRY(submit(frame, false, -1));
  while (canopyStats(host.canopy).layers.spreadRebuilds == 0) CANOPY_TRY(submit(frame, false, -1));
  CANOPY_TRY(drain());
  const CanopyStats ms = canopyStats(host.canopy);
  std::fprintf(stderr, "streamed mesh (%.1f MiB through a %.1f MiB ring): the first re-slice took %u frames (not written)\n",
               double(ms.layers.meshBytes) / double(1 << 20), double(ms.layers.meshRingBytes) / double(1 << 20),
               ms.layers.lastSpreadFrames);
  return Status();
}

// Leaf shading (the light sheet): the plant lit from the front (--light), from behind (that
// light turned 180 degrees about the vertical) and from behind without translucency; three more
// frames at the last frame's camera, each light change re-sliced at once. `written` is redirected
// to collect them.
Status writeLightSheet(const Options& o, Host& host, const uint8_t clear[3],
                       const std::function<CanopyFrame(uint32_t)>& frameAt, const SubmitFrame& submit,
                       const std::function<Status()>& drain, WrittenFrame& written) {
  std::vector<std::vector<uint8_t>> lit;
  written = [&](uint32_t, const std::vector<uint8_t>& pixels) -> Status {
    lit.push_back(pixels);
    return Status();
  };
  const Float3 behind{-o.light.x, o.light.y, -o.light.z};
  const struct { Float3 light; bool translucency; } variants[] = {{o.light, true}, {behind, true}, {behind, false}};
  for (const auto& v : variants) {
    CanopyParams p = canopyParams(host.canopy);
    p.layers.lightDirection = v.light;
    p.layers.translucency = v.translucency;
    p.layers.rebuildBudgetMs = 0.0f;
    CANOPY_TRY(setCanopyParams(host.canopy, p));
    CANOPY_TRY(submit(frameAt(o.frames - 1), false, 0));
    CANOPY_TRY(drain());
  }
  glm::uvec4 litCrop;
  CANOPY_TRY(writeContactSheet(o.outDir + "/light_sheet.png", lit, o.width, o.height, clear, &litCrop));
  std::fprintf(stderr, "wrote %s/light_sheet.png: light towards (%g, %g, %g), then (%g, %g, %g) with and without translucency\n",
               o.outDir.c_str(), o.light.x, o.light.y, o.light.z, behind.x, behind.y, behind.z);
  return Status();
}

// Writes `text` to `path` (best effort: the same text is printed too).
void writeTextFile(const std::string& path, const std::string& text) {
  if (FILE* f = std::fopen(path.c_str(), "w")) {
    std::fputs(text.c_str(), f);
    std::fclose(f);
  }
}

// A headless frame in flight: whether its timing is kept, which written frame it is, when it went.
struct InFlight {
  bool keep = false;
  int64_t index = -1;  // the written frame's number, -1 for a warm-up frame
  double submitted = 0.0;
};

// The headless run's per-frame timing: the first frame (it slices the layers; every orbit frame
// re-slices) apart from the steady frames of the sequence and from the frames held alone after it.
// Wall clock per frame: the interval between frame completions (with two frames in flight the GPU
// never idles between them), or submit-to-fence for the very first frame.
struct FrameClock {
  TimingLog first, steady, alone;
  bool held = false;  // the frames measured alone after the sequence
  bool anyDone = false;
  double lastDone = -1.0;
  void add(const std::vector<PassTiming>& t, const InFlight& p) {
    const double done = nowMs();
    const double wall = done - (lastDone >= 0.0 ? std::max(lastDone, p.submitted) : p.submitted);
    lastDone = done;
    if (!anyDone) first.add(t, wall);
    else if (p.keep) (held ? alone : steady).add(t, wall);
    anyDone = true;
  }
};

// Frame `i` of the run's camera path from `rig` (the demo's dt; the frame number is the submit's).
CanopyFrame pathFrame(const Options& o, const CameraRig& rig, const VegetationModel& model, uint32_t i) {
  CanopyFrame f;
  f.camera = toCamera(cameraPathView(cameraPathOf(o, rig), model.boundsMin, model.boundsMax, float(o.width) / float(o.height), i));
  f.dt = 1.0f / o.fps;
  return f;
}

// The frame progress: on a terminal one line rewritten in place; in a log at most one line a
// second, and the last.
void printProgress(uint32_t i, uint32_t frames, double t0, double* lastProgress) {
  const bool tty = isatty(2), lastFrame = i + 1 == frames;
  if (!tty && !lastFrame && nowMs() - *lastProgress < 1000.0) return;
  *lastProgress = nowMs();
  std::fprintf(stderr, "%sframe %u / %u (%.1f frames/s)%s", tty ? "\r" : "", i + 1, frames,
               double(i + 1) * 1000.0 / std::max(nowMs() - t0, 1e-3), tty && !lastFrame ? "" : "\n");
}

// --shadows: the direction, in shadow-map texels, along which the camera's right runs (the map's
// caster centroid is measured along it).
glm::vec2 shadowAxis(const Host& host, const VegetationModel& model, const CanopyFrame& f0) {
  const glm::vec3 right(glm::inverse(toGlm(f0.camera.view))[0]);
  const glm::vec3 c = 0.5f * (model.boundsMin + model.boundsMax);
  auto lightPixel = [&](glm::vec3 p) {
    const glm::vec4 q = host.shadow.light * glm::vec4(p, 1.0f);
    return (glm::vec2(q) / q.w * 0.5f + 0.5f) * float(Host::Shadow::kSize);
  };
  const glm::vec2 along = lightPixel(c + right) - lightPixel(c);
  return glm::length(along) > 0.0f ? glm::normalize(along) : ShadowMeter{}.axis;
}

// The sway of the written frames, measured against the host's clear colour as the frames store it.
SwayMeter swayMeterFor(const Options& o, const Host& host) {
  SwayMeter sway;
  sway.width = o.width;
  sway.height = o.height;
  for (int c = 0; c < 3; ++c) sway.clear[c] = uint8_t(std::lround(255.0f * std::clamp(host.clearSrgb[c], 0.0f, 1.0f)));
  sway.greyGround = o.shadows;
  return sway;
}

// --pusher: the sphere at written frame `index` (none for a warm-up or held frame, index < 0), and
// its screen path appended to *path, one line a frame: x y (pixels, y down) and its radius in pixels.
Status setFramePushers(const Options& o, Host& host, const VegetationModel& model, const glm::vec3& right, int64_t index,
                       const CanopyFrame& f, std::string* path) {
  if (o.pusher == PusherPath::None) return Status();
  if (index < 0) return setCanopyPushers(host.canopy, {});
  const CanopyPusher p = pusherAt(o.pusher, model.boundsMin, model.boundsMax, right, uint32_t(index), o.frames, o.fps, domainWindSpeed(o));
  const glm::mat4 view = toGlm(f.camera.view), proj = toGlm(f.camera.proj);
  const glm::vec4 q = proj * view * glm::vec4(toGlm(p.a), 1.0f);
  const float depth = -(view * glm::vec4(toGlm(p.a), 1.0f)).z;
  const float x = (q.x / q.w * 0.5f + 0.5f) * float(o.width), y = (q.y / q.w * 0.5f + 0.5f) * float(o.height);
  const float r = p.radius * std::abs(proj[1][1]) * 0.5f * float(o.height) / std::max(depth, 1e-6f);
  char line[96];
  std::snprintf(line, sizeof line, "%lld %.2f %.2f %.2f\n", static_cast<long long>(index), double(x), double(y), double(r));
  *path += line;
  return setCanopyPushers(host.canopy, {p});
}

// --shadows --debug shadow-map: a frame's shadow map as a grey PNG (near the sun dark, nothing white).
Status writeShadowMap(FrameWriter& writer, const std::string& path, const std::vector<float>& depth) {
  std::vector<uint8_t> grey(depth.size() * 4);
  for (size_t k = 0; k < depth.size(); ++k) {
    const uint8_t v = uint8_t(std::lround(255.0f * std::clamp(depth[k], 0.0f, 1.0f)));
    grey[4 * k] = grey[4 * k + 1] = grey[4 * k + 2] = v;
    grey[4 * k + 3] = 255;
  }
  return writer.push(path, Host::Shadow::kSize, Host::Shadow::kSize, grey);
}

int runHeadless(const Options& o, const VegetationModel& model, const std::string& label) {
  int messages = 0;
  Device dev;
  Status s = createDemoDevice(o, &messages, &dev);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-demo: %s\n", s.message().c_str());
    destroyDevice(dev);
    return 1;
  }
  Host host;
  FrameRing ring;
  s = [&]() -> Status {
    CANOPY_TRY(prepareOutputFolder(o));
    CANOPY_TRY(createHost(dev, model, o, o.width, o.height, true, VK_FORMAT_UNDEFINED, &host));
    const CameraRig rig0 = defaultRig(o);
    FrameClock clock;
    FrameWriter writer;
    const std::vector<size_t> picked = contactSheetFrames(o.frames);
    std::vector<std::vector<uint8_t>> sheetFrames;
    SwayMeter sway = swayMeterFor(o, host);
    const bool measureSway = o.camera == CameraMotion::Still && o.debug == CompositeDebugView::None;
    ShadowMeter shadow;
    // Warm-up: whole frames at the same dt and camera as frame 0, not written, so the wind has
    // reached the plant and the history ring (exact delay) is full when the first frame is written.
    const uint32_t warmup = uint32_t(std::lround(double(o.warmupSeconds) * o.fps));
    auto frameAt = [&](uint32_t i) { return pathFrame(o, rig0, model, i); };
    InFlight inFlight[Host::kFramesInFlight];
    uint64_t frameNumber = 0;
    CANOPY_TRY(createFrameRing(dev, &ring));
    // Frames in flight: frame n is recorded into slot n % 2 while frame n - 1 may still execute;
    // the loop waits only for the slot's previous frame (its fence), then writes that frame.
    std::function<Status(uint32_t, const std::vector<uint8_t>&)> written;  // set below
    std::function<Status(uint32_t, const std::vector<float>&)> shadowWritten;
    auto retire = [&](uint32_t slot) -> Status {
      const InFlight& p = inFlight[slot];
      bool waited = false;
      CANOPY_TRY(waitFrameSlot(dev, ring, slot, &waited));
      if (!waited) return Status();
      std::vector<PassTiming> t;
      CANOPY_TRY(host.timer[slot].read(dev, &t));
      clock.add(t, p);
      if (p.index >= 0) {
        std::vector<uint8_t> rgba;
        readPixels(host, slot, &rgba);
        CANOPY_TRY(written(uint32_t(p.index), rgba));
        if (host.shadow.readback) {
          std::vector<float> depth;
          readShadowMap(host, slot, &depth);
          CANOPY_TRY(shadowWritten(uint32_t(p.index), depth));
        }
      }
      return Status();
    };
    // --pusher: the sphere at written frame i (none in the warm-up and the held frames).
    const glm::vec3 pusherRight(glm::inverse(toGlm(frameAt(0).camera.view))[0]);
    std::string pusherPath;
    auto pushersFor = [&](int64_t index, const CanopyFrame& f) {
      return setFramePushers(o, host, model, pusherRight, index, f, &pusherPath);
    };
    auto submit = [&](CanopyFrame f, bool keep, int64_t index) -> Status {
      const uint32_t slot = uint32_t(frameNumber % Host::kFramesInFlight);
      CANOPY_TRY(retire(slot));
      CANOPY_TRY(pushersFor(index, f));
      f.frameNumber = ++frameNumber;
      CANOPY_TRY(recordFrameSlot(host, ring, slot, f, nullptr));
      VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
      si.commandBufferCount = 1;
      si.pCommandBuffers = &ring.cmds[slot];
      inFlight[slot] = {keep, index, nowMs()};
      CANOPY_VK(vkQueueSubmit(dev.queue, 1, &si, ring.fences[slot]));
      ring.pending[slot] = true;
      return Status();
    };
    // Waits for both slots, older frame first (the frames are written in order).
    auto drain = [&]() -> Status {
      CANOPY_TRY(retire(uint32_t(frameNumber % Host::kFramesInFlight)));
      return retire(uint32_t((frameNumber + 1) % Host::kFramesInFlight));
    };
    if (warmup > 0) {
      const double w0 = nowMs();
      for (uint32_t i = 0; i < warmup; ++i) CANOPY_TRY(submit(frameAt(0), false, -1));
      CANOPY_TRY(drain());
      std::fprintf(stderr, "warm-up: %u frames (%.2f s of simulation) in %.1f s\n", warmup, double(warmup) / o.fps,
                   (nowMs() - w0) / 1000.0);
    }
    if (!canopyStats(host.canopy).layers.meshResident) CANOPY_TRY(completeStreamedReslice(host, warmup, frameAt(0), submit, drain));
    const double t0 = nowMs();
    double lastProgress = t0;
    written = [&](uint32_t i, const std::vector<uint8_t>& pixels) -> Status {
      std::vector<uint8_t> rgba = pixels;
      char name[64];
      std::snprintf(name, sizeof name, "/frame_%04u.png", i);
      CANOPY_TRY(writer.push(o.outDir + name, o.width, o.height, rgba));
      if (measureSway) sway.add(rgba);
      if (std::find(picked.begin(), picked.end(), size_t(i)) != picked.end()) sheetFrames.push_back(std::move(rgba));
      printProgress(i, o.frames, t0, &lastProgress);
      return Status();
    };
    // --shadows: the map's caster centroid along where the camera's right runs in it; the map itself
    // with --debug shadow-map (near the sun dark, nothing white).
    if (o.shadows) shadow.axis = shadowAxis(host, model, frameAt(0));
    shadowWritten = [&](uint32_t i, const std::vector<float>& depth) -> Status {
      if (measureSway) shadow.add(depth, Host::Shadow::kSize);
      if (!o.debugShadowMap) return Status();
      char name[64];
      std::snprintf(name, sizeof name, "/shadow_%04u.png", i);
      return writeShadowMap(writer, o.outDir + name, depth);
    };
    for (uint32_t i = 0; i < o.frames; ++i) CANOPY_TRY(submit(frameAt(i), true, int64_t(i)));
    CANOPY_TRY(drain());
    if (o.pusher != PusherPath::None) writeTextFile(o.outDir + "/pusher_path.txt", pusherPath);
    CANOPY_TRY(writer.finish());
    // Canopy's frame with nothing else running: the last view held, one frame at a time (submit to
    // fence), no file written; the first two are not kept (a moving path's last view re-slices).
    clock.held = true;
    for (uint32_t k = 0; k < kHeldFrames + 2; ++k) {
      CANOPY_TRY(submit(frameAt(o.frames - 1), k >= 2, -1));
      CANOPY_TRY(drain());
    }
    clock.held = false;
    glm::uvec4 crop;
    CANOPY_TRY(writeContactSheet(o.outDir + "/contact_sheet.png", sheetFrames, o.width, o.height, sway.clear, &crop));
    const CanopyStats st = canopyStats(host.canopy);  // the sequence's, before the light sheet's re-slices
    if (o.lightSheet) CANOPY_TRY(writeLightSheet(o, host, sway.clear, frameAt, submit, drain, written));
    CANOPY_TRY(writer.finish());
    const std::string text =
        timingReport(o, label, dev, st, warmup, clock.first, clock.steady, clock.alone, writer.writeMs(), measureSway ? &sway : nullptr,
                     measureSway && o.shadows ? &shadow : nullptr);
    writeTextFile(o.outDir + "/timing.txt", text);
    std::printf("%s\n", text.c_str());
    printWrittenFiles(o, picked, crop);
    if (o.mp4) writeMp4(o);
    return Status();
  }();
  if (!s.ok()) std::fprintf(stderr, "canopy-demo: %s\n", s.message().c_str());
  if (dev.device) vkDeviceWaitIdle(dev.device);  // shutdown (a failure may leave frames submitted)
  destroyFrameRing(dev, ring);
  destroyHost(host);
  destroyDevice(dev);
  if (messages > 0) {
    std::fprintf(stderr, "canopy-demo: %d validation messages\n", messages);
    return 1;
  }
  return s.ok() ? 0 : 1;
}

// --compare-frames A B: each frame_NNNN.png of A against B's (tools/world_lock.h), one line each,
// then the worst of each measure. Exit 1 when a folder has no frames or the two differ in count or size.
int compareFolders(const Options& o) {
  const glm::vec3 sky = skySrgb(o);
  const uint8_t clear[3] = {uint8_t(std::lround(255.0f * sky.r)), uint8_t(std::lround(255.0f * sky.g)),
                            uint8_t(std::lround(255.0f * sky.b))};
  std::printf("world-lock error of %s against %s (covered: differs from the clear colour by > 1 level)\n", o.compareA.c_str(),
              o.compareB.c_str());
  std::printf("%6s %9s %11s %10s %10s %9s\n", "frame", "IoU", "sil. mean", "sil. p99", "centroid", "colour");
  WorldLockError worst;
  uint32_t n = 0, worstFrame = 0;
  double colourSum = 0, silSum = 0;
  // A's pusher_path.txt (--pusher): the largest per-pixel difference over the frames, measured
  // against the band the pusher's path sweeps on screen.
  std::vector<glm::vec3> path;  // x, y, radius (pixels)
  if (FILE* pf = std::fopen((o.compareA + "/pusher_path.txt").c_str(), "r")) {
    long long frame = 0;
    float x = 0, y = 0, r = 0;
    while (std::fscanf(pf, "%lld %f %f %f", &frame, &x, &y, &r) == 4) path.push_back({x, y, r});
    std::fclose(pf);
  }
  std::vector<uint8_t> maxDiff;
  uint32_t diffW = 0, diffH = 0;
  // pusher_sheet.png: for six frames spread over the run, the band's crop from A, from B and their
  // difference (x4): the grass parting where the sphere is and springing back behind it.
  std::vector<std::vector<uint8_t>> sheetRows;
  glm::ivec4 crop(0);  // x0, y0, x1, y1
  if (!path.empty()) {
    glm::vec2 lo(1e30f), hi(-1e30f);
    for (const glm::vec3& p : path) lo = glm::min(lo, glm::vec2(p) - 3.0f * p.z), hi = glm::max(hi, glm::vec2(p) + 3.0f * p.z);
    crop = glm::ivec4(int(std::floor(lo.x)), int(std::floor(lo.y)), int(std::ceil(hi.x)), int(std::ceil(hi.y)));
  }
  for (;; ++n) {
    uint32_t wa = 0, ha = 0;
    std::vector<uint8_t> a, b;
    const int rc = readFramePair(o.compareA, o.compareB, n, &wa, &ha, &a, &b);
    if (rc == 1) break;
    if (rc == 2) return 1;
    const WorldLockError e = compareFrames(a, b, wa, ha, clear);
    if (!path.empty()) {
      const uint32_t frames = uint32_t(path.size());
      const int x0 = std::max(crop.x, 0), y0 = std::max(crop.y, 0), x1 = std::min(crop.z, int(wa)), y1 = std::min(crop.w, int(ha));
      if (frames >= 6 && x1 > x0 && y1 > y0 && n % ((frames - 1) / 5) == 0 && sheetRows.size() < 6 * size_t(y1 - y0)) {
        for (int y = y0; y < y1; ++y) {
          std::vector<uint8_t> row;
          for (int part = 0; part < 3; ++part)
            for (int x = x0; x < x1; ++x) {
              const size_t k = size_t(y) * wa + size_t(x);
              for (int c = 0; c < 3; ++c)
                row.push_back(part == 0 ? a[4 * k + c] : part == 1 ? b[4 * k + c]
                                                       : uint8_t(std::min(255, 4 * std::abs(int(a[4 * k + c]) - int(b[4 * k + c])))));
              row.push_back(255);
            }
          sheetRows.push_back(std::move(row));
        }
      }
      if (maxDiff.empty()) maxDiff.assign(size_t(wa) * ha, 0), diffW = wa, diffH = ha;
      for (size_t k = 0; k < maxDiff.size() && maxDiff.size() == size_t(wa) * ha; ++k)
        for (int c = 0; c < 3; ++c)
          maxDiff[k] = std::max<uint8_t>(maxDiff[k], uint8_t(std::abs(int(a[4 * k + c]) - int(b[4 * k + c]))));
    }
    std::printf("%6u %9.4f %9.3f px %7.2f px %7.2f px %9.2f\n", n, e.coverageIoU, e.silhouetteMeanPx, e.silhouetteP99Px,
                e.centroidPx, e.colourMean);
    if (n == 0 || e.coverageIoU < worst.coverageIoU) worst.coverageIoU = e.coverageIoU, worstFrame = n;
    worst.silhouetteMeanPx = std::max(worst.silhouetteMeanPx, e.silhouetteMeanPx);
    worst.silhouetteP99Px = std::max(worst.silhouetteP99Px, e.silhouetteP99Px);
    worst.centroidPx = std::max(worst.centroidPx, e.centroidPx);
    worst.colourMean = std::max(worst.colourMean, e.colourMean);
    colourSum += e.colourMean;
    silSum += e.silhouetteMeanPx;
  }
  if (n == 0) {
    std::fprintf(stderr, "canopy-demo: no frame_0000.png in %s or %s\n", o.compareA.c_str(), o.compareB.c_str());
    return 1;
  }
  std::printf("%u frames: IoU min %.4f (frame %u); silhouette mean: worst frame %.3f px, average %.3f px; p99 worst %.2f px; "
              "centroid worst %.2f px; colour worst %.2f, average %.2f levels\n",
              n, worst.coverageIoU, worstFrame, worst.silhouetteMeanPx, silSum / n, worst.silhouetteP99Px, worst.centroidPx,
              worst.colourMean, colourSum / n);
  if (!path.empty() && !maxDiff.empty()) {
    // Pixels whose largest difference exceeds 8 levels, inside the band (within 3 radii of the
    // path's screen positions) and beyond it; the difference image: white = 32 levels or more,
    // the band's edge in red.
    const int kLevels = 8;
    uint64_t inside = 0, beyond = 0;
    std::vector<uint8_t> image(maxDiff.size() * 4, 255);
    for (uint32_t y = 0; y < diffH; ++y)
      for (uint32_t x = 0; x < diffW; ++x) {
        // Both in Vulkan's framebuffer convention: rows from the top.
        float nearest = 1e30f;
        for (const glm::vec3& p : path)
          nearest = std::min(nearest, glm::length(glm::vec2(float(x) + 0.5f - p.x, float(y) + 0.5f - p.y)) / std::max(p.z, 1e-3f));
        const size_t k = size_t(y) * diffW + x;
        const bool band = nearest <= 3.0f;
        if (maxDiff[k] > kLevels) (band ? inside : beyond)++;
        const uint8_t v = uint8_t(std::min(255, int(maxDiff[k]) * 8));
        image[4 * k] = image[4 * k + 1] = image[4 * k + 2] = v;
        if (nearest > 2.95f && nearest <= 3.0f) image[4 * k] = 255, image[4 * k + 1] = image[4 * k + 2] = 0;
      }
    if (!sheetRows.empty()) {
      std::vector<uint8_t> sheet;
      for (const std::vector<uint8_t>& row : sheetRows) sheet.insert(sheet.end(), row.begin(), row.end());
      const Status ws = writePng(o.compareA + "/pusher_sheet.png", uint32_t(sheetRows[0].size() / 4), uint32_t(sheetRows.size()), sheet);
      if (!ws.ok()) std::fprintf(stderr, "canopy-demo: %s\n", ws.message().c_str());
    }
    const std::string out = o.compareA + "/difference.png";
    const Status w = writePng(out, diffW, diffH, image);
    std::printf("pusher band (3 radii of its path, %zu frames): %llu pixels differ by > %d levels inside it, %llu beyond it "
                "(%.2f %% of the differing pixels beyond); %s%s\n",
                path.size(), static_cast<unsigned long long>(inside), kLevels, static_cast<unsigned long long>(beyond),
                inside + beyond ? 100.0 * double(beyond) / double(inside + beyond) : 0.0, out.c_str(),
                w.ok() ? "" : (" not written: " + w.message()).c_str());
  }
  return 0;
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
  if (!o.compareA.empty()) return compareFolders(o);
  if (!o.foliageWind.empty()) return measureFoliageFolders(o.foliageWind, o.foliageStill);
  if (o.cache.clear) return cli::clearCacheCommand("canopy-demo", o.cache, o.gltf);
  if (!o.gltf.empty() || !o.sceneFile.empty()) {
    const Status where = cli::resolveCacheFolder(o.cache, o.gltf.empty() ? o.sceneFile : o.gltf, &o.cacheFolder);
    if (!where.ok()) std::printf("cache: none: %s\n", where.message().c_str());
  }
  VegetationModel model;
  std::string label;
  auto copies = std::make_shared<SceneCopies>();
  const Status s = loadScene(o, &model, &label, copies.get());
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-demo: %s\n", s.message().c_str());
    return 1;
  }
  if (!o.sceneFile.empty()) o.copies = copies;
  if (o.window) {
    const int w = runWindow(o, model, label);
    if (w >= 0) return w;
    // No display: runWindow said why; the headless run writes the files instead.
    if (o.frames == 0) o.frames = Options().frames;
  }
  return runHeadless(o, model, label);
}
