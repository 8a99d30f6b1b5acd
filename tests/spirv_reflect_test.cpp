// Every pipeline's descriptor set layout is read from its shaders' SPIR-V (engine/spirv_reflect.h,
// docs/design.md "Descriptors from the SPIR-V"). These tests hold that reading against glslang's
// own reflection of the GLSL source (`glslangValidator -q`, an independent reader of the same
// declarations) for every shader embedded in the library, and check what it refuses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <unistd.h>

#include "engine/shader_registry.h"
#include "engine/spirv_reflect.h"
#include "tools/test_shaders.h"

using namespace canopy;

namespace {

enum class Kind { Buffer, Sampler, Image };

const char* kindName(Kind k) { return k == Kind::Buffer ? "buffer" : k == Kind::Sampler ? "sampler" : "image"; }

Kind kindOf(VkDescriptorType t) {
  if (t == VK_DESCRIPTOR_TYPE_STORAGE_BUFFER || t == VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER) return Kind::Buffer;
  if (t == VK_DESCRIPTOR_TYPE_STORAGE_IMAGE) return Kind::Image;
  return Kind::Sampler;
}

std::string run(const std::string& command) {
  std::string out;
  FILE* p = popen(command.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  pclose(p);
  return out;
}

// glslang's reflection of the active bindings: "name: offset -1, type 8b5e, ..., binding 4, ..."
// lines under "Uniform reflection:" (opaque types) and the block sections (buffers).
std::map<int, Kind> glslangBindings(const std::string& source, std::string* log) {
  // The include folders are the runtime's shaders/ and the public include folder (a host's view of
  // <canopy/canopy_wind.glsl>) for both registries (cmake/CanopyShaders.cmake).
  const std::string cmd = std::string(CANOPY_GLSLANG_VALIDATOR) + " -V --target-env vulkan1.2 -I" + CANOPY_SHADER_SOURCES + " -I" +
                          CANOPY_SOURCE_DIR + "/render/include -q -o /dev/null " + source + " 2>&1";
  *log = run(cmd);
  std::map<int, Kind> out;
  std::istringstream in(*log);
  std::string line, section;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == ':' && line.find(' ') != std::string::npos && line.find(',') == std::string::npos) {
      section = line;
      continue;
    }
    const size_t b = line.find(", binding ");
    if (b == std::string::npos) continue;
    const int binding = std::atoi(line.c_str() + b + 10);
    if (binding < 0) continue;
    if (section.find("block") != std::string::npos) {
      out[binding] = Kind::Buffer;
      continue;
    }
    const size_t t = line.find(", type ");
    if (t == std::string::npos) continue;
    const unsigned long type = std::strtoul(line.c_str() + t + 7, nullptr, 16);
    // GL enums of the image types (GL_IMAGE_1D .. GL_UNSIGNED_INT_IMAGE_2D_MULTISAMPLE_ARRAY).
    out[binding] = type >= 0x904C && type <= 0x906C ? Kind::Image : Kind::Sampler;
  }
  return out;
}

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string dir = testing::TempDir();
  const std::string path = dir + (dir.empty() || dir.back() == '/' ? "" : "/") + name;
  std::ofstream(path) << text;
  return path;
}

Status reflectSource(const std::string& name, const std::string& glsl, DescriptorTypes* out) {
  const std::string src = writeTemp(name, glsl), spv = src + ".spv";
  const std::string log = run(std::string(CANOPY_GLSLANG_VALIDATOR) + " -V --target-env vulkan1.2 -o " + spv + " " + src + " 2>&1");
  std::ifstream f(spv, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(f)), {});
  if (bytes.size() < 20) return Status::error("glslang did not compile " + name + ": " + log);
  return reflectDescriptors(reinterpret_cast<const uint32_t*>(bytes.data()), bytes.size() / 4, out);
}

}  // namespace

// The layout each embedded shader's pipelines are built with, against glslang's reflection of the
// same source: every binding glslang sees active is there with its kind. Both registries: the
// runtime's (shaders/) and the tests' (tests/shaders, tools/test_shaders.h).
TEST(SpirVReflect, EveryEmbeddedShaderLayoutMatchesGlslangReflection) {
  struct Registry {
    const EmbeddedShader* (*at)(size_t);
    const char* sources;
  };
  const Registry registries[] = {{&embeddedShaderAt, CANOPY_SHADER_SOURCES},
                                 {&canopy_test::embeddedShaderAt, CANOPY_TEST_SHADER_SOURCES}};
  size_t shaders = 0, testShaders = 0, bindings = 0;
  for (const Registry& r : registries) {
    for (size_t i = 0; const EmbeddedShader* sh = r.at(i); ++i) {
      SCOPED_TRACE(sh->name);
      ++(r.at == &embeddedShaderAt ? shaders : testShaders);
      DescriptorTypes ours;
      Status s = reflectDescriptors(sh->code, sh->sizeBytes / 4, &ours);
      ASSERT_TRUE(s.ok()) << s.message();
      // (No gap is checked per pipeline at creation: a fragment shader may hold only the bindings
      // after its vertex shader's, as composite_resolve.frag does.)
      std::string log;
      const std::map<int, Kind> theirs = glslangBindings(std::string(r.sources) + "/" + sh->name, &log);
      ASSERT_NE(log.find("Uniform reflection:"), std::string::npos) << "glslang printed no reflection:\n" << log;
      for (const auto& [binding, kind] : theirs) {
        ASSERT_LT(size_t(binding), ours.size()) << "glslang sees binding " << binding << " (" << kindName(kind)
                                                << "), the SPIR-V reading has " << ours.size() << " bindings";
        EXPECT_EQ(kindName(kindOf(ours[binding])), std::string(kindName(kind)))
            << "binding " << binding << ": ours " << descriptorTypeName(ours[binding]) << "\n" << log;
        ++bindings;
      }
    }
  }
  std::printf("%zu runtime shaders + %zu test shaders, %zu active bindings compared with glslang's reflection\n",
              shaders, testShaders, bindings);
  EXPECT_GT(shaders, 30u);
  EXPECT_EQ(testShaders, 8u);
  EXPECT_GT(bindings, 100u);
}

// The tests' shaders are not in the runtime a host links, and the runtime's are not duplicated
// into the tests' registry.
TEST(SpirVReflect, TestShadersLiveOutsideTheRuntime) {
  size_t n = 0;
  for (size_t i = 0; const EmbeddedShader* sh = canopy_test::embeddedShaderAt(i); ++i, ++n) {
    EXPECT_EQ(findEmbeddedShader(sh->name), nullptr) << sh->name << " is embedded in the runtime library";
    EXPECT_EQ(canopy_test::findEmbeddedShader(sh->name), sh);
  }
  for (size_t i = 0; const EmbeddedShader* sh = embeddedShaderAt(i); ++i)
    EXPECT_EQ(canopy_test::findEmbeddedShader(sh->name), nullptr) << sh->name;
  EXPECT_EQ(n, 8u);
  for (const char* name : {"example_write.comp", "interop_probe.comp", "per_vertex_probe.comp", "wind_probe.comp"})
    EXPECT_NE(canopy_test::findEmbeddedShader(name), nullptr) << name;
}

TEST(SpirVReflect, ReadsEachDescriptorKind) {
  DescriptorTypes t;
  Status s = reflectSource("kinds.comp", R"(#version 450
layout(local_size_x = 1) in;
layout(binding = 0) buffer A { float a[]; };
layout(binding = 1) uniform B { vec4 b; };
layout(binding = 2) uniform sampler2D c;
layout(binding = 3, r32f) uniform image2D d;
layout(binding = 4) uniform texture2D e;
layout(binding = 5) uniform sampler f;
layout(push_constant) uniform P { float p; };
void main() { a[0] = b.x + p; }
)", &t);
  ASSERT_TRUE(s.ok()) << s.message();
  const DescriptorTypes want = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,         VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
                                VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
                                VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE,          VK_DESCRIPTOR_TYPE_SAMPLER};
  EXPECT_EQ(t, want);
}

TEST(SpirVReflect, RefusesWhatAPushDescriptorListCannotBind) {
  DescriptorTypes t;
  Status s = reflectSource("set1.comp", "#version 450\nlayout(local_size_x = 1) in;\n"
                                        "layout(set = 1, binding = 0) buffer A { float a[]; };\nvoid main() { a[0] = 1; }\n", &t);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("descriptor set 1"), std::string::npos) << s.message();

  s = reflectSource("array.frag", "#version 450\nlayout(binding = 0) uniform sampler2D tex[2];\n"
                                  "layout(location = 0) out vec4 o;\nvoid main() { o = texture(tex[1], vec2(0)); }\n", &t);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("array of descriptors"), std::string::npos) << s.message();

  s = reflectSource("gap.comp", "#version 450\nlayout(local_size_x = 1) in;\nlayout(binding = 0) buffer A { float a[]; };\n"
                                "layout(binding = 2) buffer C { float c[]; };\nvoid main() { a[0] = c[0]; }\n", &t);
  ASSERT_TRUE(s.ok()) << s.message();
  s = requireContiguous(t, "gap.comp");
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("binding 1 is declared by no stage"), std::string::npos) << s.message();

  DescriptorTypes merged;
  s = mergeDescriptors({VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}, {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER}, "pair", &merged);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("binding 0 is a storage buffer in one stage and a combined image sampler"), std::string::npos)
      << s.message();
  s = mergeDescriptors({VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}, {VK_DESCRIPTOR_TYPE_MAX_ENUM, VK_DESCRIPTOR_TYPE_SAMPLER}, "pair",
                       &merged);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(merged, (DescriptorTypes{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_SAMPLER}));
}

TEST(SpirVReflect, RefusesAMalformedModule) {
  DescriptorTypes t;
  const EmbeddedShader* sh = findEmbeddedShader("composite_tiles.comp");
  ASSERT_NE(sh, nullptr);
  std::vector<uint32_t> words(sh->code, sh->code + sh->sizeBytes / 4);
  ASSERT_TRUE(reflectDescriptors(words.data(), words.size(), &t).ok());
  EXPECT_EQ(t.size(), 9u);  // bindings 0..8 (8: the reprojection view block)
  // Cut at the first instruction boundary past the middle, then an instruction whose length runs
  // past the end (a word inside an instruction would be read as an operand, not as a header).
  size_t boundary = 5;
  while (boundary < words.size() / 2) boundary += std::max<uint32_t>(words[boundary] >> 16, 1u);
  std::vector<uint32_t> cut(words.begin(), words.begin() + boundary);
  cut.push_back(0x7fff0047u);
  EXPECT_FALSE(reflectDescriptors(cut.data(), cut.size(), &t).ok());
  words[0] = 0;
  Status s = reflectDescriptors(words.data(), words.size(), &t);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("not a SPIR-V module"), std::string::npos) << s.message();
  EXPECT_FALSE(reflectDescriptors(nullptr, 0, &t).ok());
}
