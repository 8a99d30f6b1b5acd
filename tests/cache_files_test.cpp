// Canopy's files under a hostile folder (docs/design.md "Files"; docs/reliability.md "Files"):
// engine/files.h's one way to open a file and render/cache_file.h's never-trusted caches. Links
// at the final and temporary names, FIFOs and folders at a cache's name, an injected full disk
// (RLIMIT_FSIZE), truncated / bit-flipped / oversized / foreign caches, writers racing, the
// folder's cap and its clearing, the user's cache folder. No GPU.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <set>

#include "engine/files.h"
#include <canopy/canopy.h>

#include "render/cache_file.h"
#include "render/leaf_roots.h"

using namespace canopy;
namespace fs = std::filesystem;

namespace {

// A fresh folder per test under the system's temporary folder.
std::string freshFolder(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("canopy_cache_files_" + std::to_string(::getpid())) / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

void spit(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << bytes;
}

std::vector<uint8_t> pattern(size_t n, uint32_t seed) {
  std::vector<uint8_t> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = uint8_t((i * 2654435761u + seed * 40503u) >> 13);
  return v;
}

std::set<std::string> listing(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

bool isLink(const std::string& p) { return fs::is_symlink(fs::symlink_status(p)); }

constexpr uint64_t kKey = 0x1234567890abcdefull;

}  // namespace

// ---- engine/files.h --------------------------------------------------------------------------------

TEST(Files, AWriteReplacesALinkAtTheFinalNameAndNeverOpensATemporaryName) {
  const std::string dir = freshFolder("links");
  const std::string victim = dir + "/victim.txt", target = dir + "/m.gltf.leafroots";
  spit(victim, "the user's own file");
  fs::create_symlink(victim, target);
  fs::create_symlink(victim, target + ".tmp");  // the name the writer used before issue 32
  const std::vector<uint8_t> data = pattern(100000, 1);
  ASSERT_TRUE(writeFileAtomically(target, {{data.data(), data.size()}}).ok());
  EXPECT_EQ(slurp(victim), "the user's own file");
  EXPECT_FALSE(isLink(target)) << "the link was followed, not replaced";
  EXPECT_TRUE(isLink(target + ".tmp"));
  EXPECT_EQ(slurp(target), std::string(data.begin(), data.end()));
  struct stat st;
  ASSERT_EQ(::lstat(target.c_str(), &st), 0);
  EXPECT_TRUE(S_ISREG(st.st_mode));
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(listing(dir), (std::set<std::string>{"victim.txt", "m.gltf.leafroots", "m.gltf.leafroots.tmp"}));
}

TEST(Files, AFifoOrAFolderAtTheNameIsRefusedAtOnce) {
  const std::string dir = freshFolder("fifo");
  const std::string fifo = dir + "/f.impostors", folder = dir + "/d.impostors";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  fs::create_directory(folder);
  FileReadOptions o;
  o.maxBytes = 1 << 20;
  o.followFinalLink = false;
  std::vector<unsigned char> bytes;
  const auto t0 = std::chrono::steady_clock::now();
  Status s = readWholeFile(fifo, o, &bytes);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
  EXPECT_NE(s.message().find("not a regular file (a FIFO)"), std::string::npos) << s.message();
  s = readWholeFile(folder, o, &bytes);
  EXPECT_NE(s.message().find("not a regular file (a directory)"), std::string::npos) << s.message();
  // A write replaces the FIFO; a folder at the name makes it fail, naming the path, leaving nothing.
  const std::string data = "payload";
  EXPECT_TRUE(writeFileAtomically(fifo, {{data.data(), data.size()}}).ok());
  EXPECT_EQ(slurp(fifo), data);
  s = writeFileAtomically(folder, {{data.data(), data.size()}});
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("'" + folder + "'"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("Is a directory"), std::string::npos) << s.message();
  EXPECT_TRUE(fs::is_directory(folder));
  EXPECT_EQ(listing(dir), (std::set<std::string>{"f.impostors", "d.impostors"}));
}

TEST(Files, ALinkIsReadOnlyWhereTheFileMayBeALink) {
  const std::string dir = freshFolder("readlink");
  spit(dir + "/real", "abc");
  fs::create_symlink(dir + "/real", dir + "/link");
  std::vector<unsigned char> bytes;
  FileReadOptions o;
  o.maxBytes = 100;
  EXPECT_TRUE(readWholeFile(dir + "/link", o, &bytes).ok());  // a model may be a link (the loader)
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "abc");
  o.followFinalLink = false;                                    // a cache may not
  const Status s = readWholeFile(dir + "/link", o, &bytes);
  EXPECT_NE(s.message().find("a symbolic link"), std::string::npos) << s.message();
  EXPECT_TRUE(bytes.empty());
  o.maxBytes = 2;
  o.followFinalLink = true;
  EXPECT_NE(readWholeFile(dir + "/real", o, &bytes).message().find("3 bytes exceeds the limit of 2"), std::string::npos);
}

TEST(Files, AFullDiskLeavesNoPartialFileAndTheOldContentsIntact) {
  // An injected write failure: the file-size limit makes write() fail with EFBIG past 64 KiB, as a
  // full disk fails with ENOSPC (the shell test fills a real tmpfs).
  const std::string dir = freshFolder("full");
  const std::string target = dir + "/c.leafroots";
  spit(target, "old cache");
  struct rlimit old;
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  const auto previous = ::signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = old;
  small.rlim_cur = 64 << 10;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const std::vector<uint8_t> data = pattern(1 << 20, 2);
  const Status s = writeFileAtomically(target, {{data.data(), 1000}, {data.data(), data.size()}});
  ::setrlimit(RLIMIT_FSIZE, &old);
  ::signal(SIGXFSZ, previous);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), Result::FileError);
  EXPECT_NE(s.message().find("'" + target + "'"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("File too large after 65536 of 1049576 bytes"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("nothing was left behind"), std::string::npos) << s.message();
  EXPECT_EQ(slurp(target), "old cache");
  EXPECT_EQ(listing(dir), std::set<std::string>{"c.leafroots"});
}

TEST(Files, AMissingFolderIsNamed) {
  const std::string dir = freshFolder("missing") + "/not/there";
  const std::string data = "x";
  const Status s = writeFileAtomically(dir + "/c.leafroots", {{data.data(), 1}});
  EXPECT_NE(s.message().find("its folder '" + dir + "': No such file or directory"), std::string::npos) << s.message();
}

// ---- render/cache_file.h ----------------------------------------------------------------------------

TEST(CacheFile, ARoundTripGivesThePayloadBack) {
  const std::string dir = freshFolder("roundtrip");
  const std::string path = dir + "/m.leafroots";
  const std::vector<uint8_t> data = pattern(4000, 3);
  ASSERT_TRUE(writeCacheFile(path, CacheKind::LeafRoots, kKey, data.data(), data.size(), 0).ok());
  EXPECT_EQ(fs::file_size(path), kCacheHeaderBytes + data.size());
  std::vector<uint8_t> back;
  std::string why;
  ASSERT_TRUE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why)) << why;
  EXPECT_EQ(back, data);
  // Absent, another key, another size, another kind.
  EXPECT_FALSE(readCacheFile(path + "x", CacheKind::LeafRoots, kKey, data.size(), &back, &why));
  EXPECT_EQ(why, "no cache file");
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey + 1, data.size(), &back, &why));
  EXPECT_NE(why.find("made for other data"), std::string::npos) << why;
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size() + 4, &back, &why));
  EXPECT_NE(why.find("made for other data"), std::string::npos) << why;
  EXPECT_FALSE(readCacheFile(path, CacheKind::ImpostorViews, kKey, data.size(), &back, &why));
  EXPECT_EQ(why, "a leaf-root cache, not a impostor-view cache");
  EXPECT_TRUE(back.empty());
}

TEST(CacheFile, EveryTruncationAndAnyOversizeIsRejected) {
  const std::string dir = freshFolder("truncated");
  const std::string path = dir + "/m.impostors";
  const std::vector<uint8_t> data = pattern(300, 4);
  ASSERT_TRUE(writeCacheFile(path, CacheKind::ImpostorViews, kKey, data.data(), data.size(), 0).ok());
  const std::string whole = slurp(path);
  std::vector<uint8_t> back;
  std::string why;
  for (size_t n = 0; n < whole.size(); ++n) {
    spit(path, whole.substr(0, n));
    EXPECT_FALSE(readCacheFile(path, CacheKind::ImpostorViews, kKey, data.size(), &back, &why)) << n;
    EXPECT_NE(why.find(n < 8 ? "truncated" : n < kCacheHeaderBytes ? "shorter than the header" : "truncated: "), std::string::npos)
        << n << ": " << why;
  }
  for (const size_t extra : {size_t(1), size_t(4096)}) {
    spit(path, whole + std::string(extra, '\0'));
    EXPECT_FALSE(readCacheFile(path, CacheKind::ImpostorViews, kKey, data.size(), &back, &why));
    EXPECT_NE(why.find("oversized: " + std::to_string(whole.size() + extra) + " bytes, the header says " +
                       std::to_string(whole.size())),
              std::string::npos)
        << why;
  }
  spit(path, whole);
  EXPECT_TRUE(readCacheFile(path, CacheKind::ImpostorViews, kKey, data.size(), &back, &why)) << why;
}

TEST(CacheFile, EveryBitFlipIsRejected) {
  const std::string dir = freshFolder("bitflip");
  const std::string path = dir + "/m.leafroots";
  const std::vector<uint8_t> data = pattern(256, 5);
  ASSERT_TRUE(writeCacheFile(path, CacheKind::LeafRoots, kKey, data.data(), data.size(), 0).ok());
  const std::string whole = slurp(path);
  std::vector<uint8_t> back;
  std::string why;
  std::set<std::string> reasons;
  for (size_t bit = 0; bit < whole.size() * 8; ++bit) {
    std::string flipped = whole;
    flipped[bit / 8] = char(flipped[bit / 8] ^ (1 << (bit % 8)));
    spit(path, flipped);
    EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why)) << "bit " << bit;
    reasons.insert(why);
  }
  // Magic, header checksum and contents' checksum each caught some.
  EXPECT_TRUE(reasons.count("damaged: the header's checksum does not match"));
  EXPECT_TRUE(reasons.count("damaged: the contents' checksum does not match"));
  EXPECT_TRUE(reasons.count("not a Canopy cache of this format (an older Canopy's file or another file)"));
}

TEST(CacheFile, AnotherVersionFormatOrAHugeClaimedSizeIsRejectedBeforeAllocating) {
  const std::string dir = freshFolder("version");
  const std::string path = dir + "/m.leafroots";
  const std::vector<uint8_t> data = pattern(64, 6);
  ASSERT_TRUE(writeCacheFile(path, CacheKind::LeafRoots, kKey, data.data(), data.size(), 0).ok());
  const std::string whole = slurp(path);
  auto resealed = [&](auto edit) {
    CacheHeader h;
    std::memcpy(&h, whole.data(), sizeof h);
    edit(h);
    h.headerChecksum = cacheHeaderChecksum(h);
    std::string out = whole;
    std::memcpy(out.data(), &h, sizeof h);
    spit(path, out);
  };
  std::vector<uint8_t> back;
  std::string why;
  resealed([](CacheHeader& h) { h.canopyVersion = CANOPY_MAKE_VERSION(0, 1, 0); });
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why));
  EXPECT_NE(why.find("made by Canopy 0.1.0, this is"), std::string::npos) << why;
  resealed([](CacheHeader& h) { h.format = 3; });
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why));
  EXPECT_EQ(why, "format version 3, this Canopy reads 2");
  resealed([](CacheHeader& h) { h.payloadBytes = ~0ull - 64; });  // a file claiming 16 EiB
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why));
  EXPECT_NE(why.find("made for other data"), std::string::npos) << why;
  // The headerless format-1 file of earlier Canopy versions.
  spit(path, std::string("CNPYLRT1") + std::string(16 + 64, '\0'));
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why));
  EXPECT_NE(why.find("not a Canopy cache of this format"), std::string::npos) << why;
}

TEST(CacheFile, LinksFifosFoldersAndOtherUsersFilesAreNotRead) {
  const std::string dir = freshFolder("foreign");
  const std::string path = dir + "/m.leafroots", real = dir + "/elsewhere";
  const std::vector<uint8_t> data = pattern(64, 7);
  ASSERT_TRUE(writeCacheFile(real, CacheKind::LeafRoots, kKey, data.data(), data.size(), 0).ok());
  std::vector<uint8_t> back;
  std::string why;
  fs::create_symlink(real, path);  // a valid cache behind a link is still not Canopy's own file
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why));
  EXPECT_NE(why.find("a symbolic link"), std::string::npos) << why;
  fs::remove(path);
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
  EXPECT_EQ(why, "not a regular file (a FIFO)");
  fs::remove(path);
  fs::create_directory(path);
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why));
  EXPECT_EQ(why, "not a regular file (a directory)");
  fs::remove(path);
  if (::geteuid() != 0) {
    std::printf("[  NOTE    ] not root: the other-user case needs chown, not run\n");
    return;
  }
  fs::copy_file(real, path);
  ASSERT_EQ(::chown(path.c_str(), 65534, 65534), 0);
  EXPECT_FALSE(readCacheFile(path, CacheKind::LeafRoots, kKey, data.size(), &back, &why));
  EXPECT_EQ(why, "owned by another user (uid 65534), not used");
}

TEST(CacheFile, WritersRacingEachOtherAndReadersAlwaysLeaveAWholeCache) {
  // Two processes write the same cache 40 times each (two different valid payloads) while this one
  // reads it: every read is absent or one whole payload, and the last state is a valid cache.
  const std::string dir = freshFolder("race");
  const std::string path = dir + "/m.impostors";
  const size_t n = 256 << 10;
  const std::vector<uint8_t> a = pattern(n, 8), b = pattern(n, 9);
  pid_t children[2];
  for (int c = 0; c < 2; ++c) {
    children[c] = ::fork();
    ASSERT_GE(children[c], 0);
    if (children[c] == 0) {
      const std::vector<uint8_t>& mine = c == 0 ? a : b;
      int failures = 0;
      for (int k = 0; k < 40; ++k)
        failures += !writeCacheFile(path, CacheKind::ImpostorViews, kKey, mine.data(), mine.size(), 0).ok();
      ::_exit(failures);
    }
  }
  int reads = 0, hits = 0;
  std::vector<uint8_t> back;
  std::string why;
  for (bool running = true; running;) {
    running = false;
    for (pid_t p : children) running |= ::waitpid(p, nullptr, WNOHANG) == 0;
    ++reads;
    if (readCacheFile(path, CacheKind::ImpostorViews, kKey, n, &back, &why)) {
      ++hits;
      EXPECT_TRUE(back == a || back == b);
    } else {
      EXPECT_EQ(why, "no cache file");
    }
  }
  for (pid_t p : children) {
    int status = 0;
    ::waitpid(p, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "a writer failed";
  }
  EXPECT_TRUE(readCacheFile(path, CacheKind::ImpostorViews, kKey, n, &back, &why)) << why;
  EXPECT_TRUE(back == a || back == b);
  EXPECT_EQ(listing(dir), std::set<std::string>{"m.impostors"});  // no temporary left
  std::printf("[  NOTE    ] %d reads during the race, %d whole caches\n", reads, hits);
}

TEST(CacheFile, TheFolderStaysUnderItsCapLeastRecentlyUsedFirst) {
  const std::string dir = freshFolder("cap");
  const size_t n = 100 << 10;
  const uint64_t each = kCacheHeaderBytes + n, cap = 3 * each + 10;
  const std::vector<uint8_t> data = pattern(n, 10);
  const char* names[] = {"a.leafroots", "b.impostors", "c.leafroots"};
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(writeCacheFile(dir + "/" + names[i], CacheKind::LeafRoots, kKey, data.data(), n, cap).ok());
    const struct timespec t[2] = {{1000000 + i * 10, 0}, {1000000 + i * 10, 0}};  // a oldest, c newest
    ASSERT_EQ(::utimensat(AT_FDCWD, (dir + "/" + names[i]).c_str(), t, 0), 0);
  }
  spit(dir + "/notes.txt", std::string(500000, 'x'));  // not Canopy's: neither counted nor removed
  std::vector<uint8_t> back;
  std::string why;
  ASSERT_TRUE(readCacheFile(dir + "/a.leafroots", CacheKind::LeafRoots, kKey, n, &back, &why)) << why;  // a: used now
  std::string note;
  ASSERT_TRUE(writeCacheFile(dir + "/d.impostors", CacheKind::LeafRoots, kKey, data.data(), n, cap, &note).ok());
  EXPECT_EQ(listing(dir), (std::set<std::string>{"a.leafroots", "c.leafroots", "d.impostors", "notes.txt"}));
  EXPECT_EQ(note, "evicted 1 least recently used cache files (0.1 MiB)");
  EXPECT_EQ(cacheFolderUsage(dir).bytes, 3 * each);
  // A cache larger than the cap by itself is not written.
  const Status s = writeCacheFile(dir + "/e.impostors", CacheKind::ImpostorViews, kKey, data.data(), n, each - 1);
  EXPECT_NE(s.message().find("would exceed the cache cap"), std::string::npos) << s.message();
  EXPECT_FALSE(fs::exists(dir + "/e.impostors"));
}

TEST(CacheFile, ClearingRemovesCanopysNamesOnlyAndNeverALinksTarget) {
  const std::string dir = freshFolder("clear");
  const std::string victim = freshFolder("clear_victim") + "/victim.leafroots";
  spit(victim, "the user's own file");
  const std::vector<uint8_t> data = pattern(1000, 11);
  ASSERT_TRUE(writeCacheFile(dir + "/a.leafroots", CacheKind::LeafRoots, kKey, data.data(), data.size(), 0).ok());
  ASSERT_TRUE(writeCacheFile(dir + "/b.impostors", CacheKind::ImpostorViews, kKey, data.data(), data.size(), 0).ok());
  fs::create_symlink(victim, dir + "/c.leafroots");
  ASSERT_EQ(::mkfifo((dir + "/d.impostors").c_str(), 0600), 0);
  spit(dir + "/e.leafroots.tmp-1-2-3", "interrupted");
  spit(dir + "/notes.txt", "mine");
  fs::create_directory(dir + "/sub.leafroots");
  uint64_t files = 0, bytes = 0;
  ASSERT_TRUE(clearCacheFolder(dir, &files, &bytes).ok());
  EXPECT_EQ(files, 5u);
  EXPECT_EQ(bytes, 2 * (kCacheHeaderBytes + 1000) + 11);
  EXPECT_EQ(listing(dir), (std::set<std::string>{"notes.txt", "sub.leafroots"}));
  EXPECT_EQ(slurp(victim), "the user's own file");
}

TEST(CacheFile, StaleTemporariesOfInterruptedWritesAreRemovedByTheNextWrite) {
  const std::string dir = freshFolder("stale");
  spit(dir + "/x.leafroots.tmp-1-0-0", "old");
  spit(dir + "/y.leafroots.tmp-2-0-0", "recent");
  const struct timespec t[2] = {{1000, 0}, {1000, 0}};
  ASSERT_EQ(::utimensat(AT_FDCWD, (dir + "/x.leafroots.tmp-1-0-0").c_str(), t, 0), 0);
  const std::vector<uint8_t> data = pattern(10, 12);
  ASSERT_TRUE(writeCacheFile(dir + "/x.leafroots", CacheKind::LeafRoots, kKey, data.data(), data.size(), 1 << 20).ok());
  EXPECT_EQ(listing(dir), (std::set<std::string>{"x.leafroots", "y.leafroots.tmp-2-0-0"}));
}

TEST(CacheFile, ModelsWithTheSameFileNameGetTheirOwnCacheAndBesideTheModelKeepsItsName) {
  const std::string root = freshFolder("names");
  fs::create_directories(root + "/a");
  fs::create_directories(root + "/b");
  fs::create_directories(root + "/cache");
  spit(root + "/a/tree.glb", "1");
  spit(root + "/b/tree.glb", "2");
  const std::string ca = cacheFilePath(root + "/a/tree.glb", root + "/cache", CacheKind::LeafRoots);
  const std::string cb = cacheFilePath(root + "/b/tree.glb", root + "/cache", CacheKind::LeafRoots);
  EXPECT_NE(ca, cb);
  EXPECT_EQ(ca.rfind(root + "/cache/tree.glb-", 0), 0u) << ca;
  EXPECT_EQ(ca.substr(ca.size() - 10), ".leafroots");
  // The same model through another spelling of its path: the same cache.
  EXPECT_EQ(cacheFilePath(root + "/b/../a/./tree.glb", root + "/cache", CacheKind::LeafRoots), ca);
  EXPECT_EQ(cacheFilePath(root + "/a/tree.glb", root + "/a", CacheKind::ImpostorViews), root + "/a/tree.glb.impostors");
  EXPECT_EQ(leafRootCachePath(root + "/a/tree.glb"), root + "/a/tree.glb.leafroots");
}

TEST(CacheFile, TheUserCacheFolderIsXdgsOrHomesAndPrivate) {
  const std::string root = freshFolder("xdg");
  const char* oldXdg = std::getenv("XDG_CACHE_HOME");
  const char* oldHome = std::getenv("HOME");
  const std::string savedXdg = oldXdg ? oldXdg : "", savedHome = oldHome ? oldHome : "";
  std::string folder;
  ::setenv("XDG_CACHE_HOME", (root + "/xdg").c_str(), 1);
  ASSERT_TRUE(userCacheFolder(&folder).ok());
  EXPECT_EQ(folder, root + "/xdg/canopy");
  struct stat st;
  ASSERT_EQ(::stat(folder.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  ::setenv("XDG_CACHE_HOME", "relative/ignored", 1);  // XDG: a relative path is ignored
  ::setenv("HOME", (root + "/home").c_str(), 1);
  fs::create_directories(root + "/home");
  ASSERT_TRUE(userCacheFolder(&folder).ok());
  EXPECT_EQ(folder, root + "/home/.cache/canopy");
  ASSERT_EQ(::stat((root + "/home/.cache").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  // A link planted at Canopy's folder is not used.
  ::setenv("XDG_CACHE_HOME", (root + "/planted").c_str(), 1);
  fs::create_directories(root + "/planted");
  fs::create_directories(root + "/elsewhere");
  fs::create_symlink(root + "/elsewhere", root + "/planted/canopy");
  Status s = userCacheFolder(&folder);
  EXPECT_NE(s.message().find("is not a folder (a link or a file): not used"), std::string::npos) << s.message();
  EXPECT_TRUE(folder.empty());
  ::unsetenv("XDG_CACHE_HOME");
  ::unsetenv("HOME");
  s = userCacheFolder(&folder);
  EXPECT_NE(s.message().find("neither XDG_CACHE_HOME nor HOME"), std::string::npos) << s.message();
  if (oldXdg) ::setenv("XDG_CACHE_HOME", savedXdg.c_str(), 1);
  if (oldHome) ::setenv("HOME", savedHome.c_str(), 1);
}
