// `skelcd check --threads 1` and `--threads 4` write the same log, byte for byte except the
// timings: every dataset and attribute of the two HDF5 files is read back through the HDF5 C API
// (not our reader, so nothing the reader skips escapes the comparison) and compared, leaving out
// only the /frames columns that hold microseconds and the root attributes command_line and
// start_time. On a real character (bvh, dynamic, auto) and a generated rig (bvh, dynamic).

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "culling/elementary.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/log/log_reader.hpp"

namespace {

using skelcd::test::run_skelcd;

const std::string kCharacter = skelcd::test::assimp_model("X/BCN_Epileptic.X").string();

bool is_timing(const std::string& member) {
  return member.size() > 3 && member.compare(member.size() - 3, 3, "_us") == 0;
}

/// The canonical content of a dataset or attribute: its shape, then its values — strings as
/// text, numbers and enums in native layout, compounds member by member without timing members.
class Reader {
 public:
  std::map<std::string, std::string> items;  // "/path" or "/path@attribute" → content
  std::vector<std::string> skipped;          // timing members left out, "/path.member"

  std::string content(hid_t object, bool attribute, const std::string& where) {
    const hid_t file_type = attribute ? H5Aget_type(object) : H5Dget_type(object);
    const hid_t space = attribute ? H5Aget_space(object) : H5Dget_space(object);
    const hssize_t n = H5Sget_simple_extent_npoints(space);
    std::string out = "n=" + std::to_string(n) + ";";
    const H5T_class_t cls = H5Tget_class(file_type);
    if (cls == H5T_STRING && H5Tis_variable_str(file_type) > 0) {
      const hid_t mem = H5Tcopy(H5T_C_S1);
      H5Tset_size(mem, H5T_VARIABLE);
      H5Tset_cset(mem, H5Tget_cset(file_type));
      std::vector<char*> strings(static_cast<std::size_t>(n));
      const herr_t ok = attribute ? H5Aread(object, mem, strings.data())
                                  : H5Dread(object, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                            strings.data());
      EXPECT_GE(ok, 0) << where;
      for (char* s : strings) {
        out += (s != nullptr ? std::string(s) : std::string("<null>")) + '\n';
      }
      if (ok >= 0) H5Dvlen_reclaim(mem, space, H5P_DEFAULT, strings.data());
      H5Tclose(mem);
    } else {
      hid_t mem = -1;
      std::vector<std::string> string_members;
      if (cls == H5T_COMPOUND) {
        // Same members minus the timings, each in its native type, packed.
        std::vector<std::pair<std::string, hid_t>> members;
        std::size_t size = 0;
        for (int i = 0; i < H5Tget_nmembers(file_type); ++i) {
          char* name = H5Tget_member_name(file_type, static_cast<unsigned>(i));
          const std::string member(name);
          H5free_memory(name);
          // /checksums' CRC of the /frames rows (and its own CRC) covers their timings too.
          if (is_timing(member) ||
              (where == "/checksums" && (member == "frames_crc" || member == "self_crc"))) {
            skipped.push_back(where + "." + member);
            continue;
          }
          const hid_t member_type = H5Tget_member_type(file_type, static_cast<unsigned>(i));
          if (H5Tget_class(member_type) == H5T_STRING) {  // e.g. /event_bones' names
            string_members.push_back(member);
            H5Tclose(member_type);
            continue;
          }
          const hid_t native = H5Tget_native_type(member_type, H5T_DIR_ASCEND);
          H5Tclose(member_type);
          size += H5Tget_size(native);
          members.emplace_back(member, native);
        }
        mem = H5Tcreate(H5T_COMPOUND, size);
        std::size_t offset = 0;
        for (const auto& [member, native] : members) {
          H5Tinsert(mem, member.c_str(), offset, native);
          offset += H5Tget_size(native);
          out += member + ",";
          H5Tclose(native);
        }
      } else if (cls == H5T_STRING) {
        mem = H5Tcopy(file_type);
      } else {
        mem = H5Tget_native_type(file_type, H5T_DIR_ASCEND);
      }
      std::vector<char> bytes(static_cast<std::size_t>(n) * H5Tget_size(mem));
      const herr_t ok = attribute ? H5Aread(object, mem, bytes.data())
                                  : H5Dread(object, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                            bytes.data());
      EXPECT_GE(ok, 0) << where;
      out.append(bytes.begin(), bytes.end());
      H5Tclose(mem);
      // String members of a compound table, read one member at a time as variable-length text.
      for (const auto& member : string_members) {
        const hid_t text = H5Tcopy(H5T_C_S1);
        H5Tset_size(text, H5T_VARIABLE);
        H5Tset_cset(text, H5T_CSET_UTF8);
        const hid_t one = H5Tcreate(H5T_COMPOUND, sizeof(char*));
        H5Tinsert(one, member.c_str(), 0, text);
        std::vector<char*> strings(static_cast<std::size_t>(n));
        const herr_t read = H5Dread(object, one, H5S_ALL, H5S_ALL, H5P_DEFAULT, strings.data());
        EXPECT_GE(read, 0) << where << "." << member;
        out += member + ":";
        for (char* str : strings) out += (str != nullptr ? std::string(str) : "<null>") + '\n';
        if (read >= 0) H5Dvlen_reclaim(one, space, H5P_DEFAULT, strings.data());
        H5Tclose(one);
        H5Tclose(text);
      }
    }
    H5Sclose(space);
    H5Tclose(file_type);
    return out;
  }

  void attributes(hid_t object, const std::string& path) {
    struct Context {
      Reader* reader;
      std::string path;
    } context{this, path};
    hsize_t index = 0;
    H5Aiterate2(object, H5_INDEX_NAME, H5_ITER_INC, &index,
                [](hid_t location, const char* name, const H5A_info_t*, void* data) -> herr_t {
                  auto& c = *static_cast<Context*>(data);
                  const std::string attribute(name);
                  if (c.path == "/" && (attribute == "command_line" || attribute == "start_time")) {
                    c.reader->skipped.push_back("/@" + attribute);
                    return 0;
                  }
                  const hid_t a = H5Aopen(location, name, H5P_DEFAULT);
                  const std::string key = c.path + "@" + attribute;
                  c.reader->items[key] = c.reader->content(a, true, key);
                  H5Aclose(a);
                  return 0;
                },
                &context);
  }

  void group(hid_t g, const std::string& path) {
    attributes(g, path);
    struct Context {
      Reader* reader;
      std::string path;
    } context{this, path};
    H5Literate(g, H5_INDEX_NAME, H5_ITER_INC, nullptr,
               [](hid_t location, const char* name, const H5L_info_t*, void* data) -> herr_t {
                 auto& c = *static_cast<Context*>(data);
                 const std::string child = (c.path == "/" ? "/" : c.path + "/") + name;
                 const hid_t object = H5Oopen(location, name, H5P_DEFAULT);
                 if (H5Iget_type(object) == H5I_GROUP) {
                   c.reader->group(object, child);
                 } else if (H5Iget_type(object) == H5I_DATASET) {
                   c.reader->attributes(object, child);
                   c.reader->items[child] = c.reader->content(object, false, child);
                 } else {
                   ADD_FAILURE() << child << ": neither group nor dataset";
                 }
                 H5Oclose(object);
                 return 0;
               },
               &context);
  }
};

Reader read_all(const std::string& path) {
  Reader reader;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(file, 0) << path;
  if (file < 0) return reader;
  reader.group(file, "/");
  H5Fclose(file);
  return reader;
}

/// Runs check with --threads 1 and `threads` and compares the two logs; returns the serial log.
skelcd::tools::LogData expect_same_logs(
    const std::string& model,
    const std::string& method,
    const std::vector<std::string>& extra,
    const std::string& tag,
    const char* threads = "4") {
  const auto dir = skelcd::test::temp_dir("parallel-" + tag);
  std::string logs[2];
  for (const int k : {0, 1}) {
    logs[k] = (dir / (k == 0 ? "serial.h5" : "parallel.h5")).string();
    std::vector<std::string> args{
        "check",
        model,
        "--method",
        method,
        "--threads",
        k == 0 ? "1" : threads,
        "-o",
        logs[k],
        "--json"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_skelcd(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
  }
  const Reader serial = read_all(logs[0]);
  const Reader parallel = read_all(logs[1]);
  EXPECT_GT(serial.items.size(), 20u);  // root attributes, /parts, /frames, /contacts, …
  EXPECT_EQ(serial.items.size(), parallel.items.size());
  for (const auto& [key, value] : serial.items) {
    const auto it = parallel.items.find(key);
    if (it == parallel.items.end()) {
      ADD_FAILURE() << key << " missing from the parallel log";
      continue;
    }
    EXPECT_TRUE(it->second == value) << key << " differs";
  }
  // Exactly the timings and the two run-specific attributes were left out.
  EXPECT_EQ(serial.skipped, parallel.skipped);
  EXPECT_EQ(serial.skipped.size(), 2u + 7u + 2u) << "skin, refit, classify, merge, traverse, "
                                                    "elementary, total; frames_crc, self_crc";
  return skelcd::tools::read_log(logs[0]);
}

TEST(ParallelCheck, RealCharacterLogsEqualSerialExceptTimings) {
  for (const char* method : {"bvh", "dynamic", "auto"}) {
    SCOPED_TRACE(method);
    const auto log = expect_same_logs(kCharacter, method, {"--frames", "36:47"},
                                      std::string("bcn-") + method);
    EXPECT_EQ(log.frames.size(), 12u + 11u);
    EXPECT_GT(log.contacts.size() + log.dcd_pairs.size(), 0u) << "nothing found: proves nothing";
  }
}

TEST(ParallelCheck, WholeClipOfABundledCharacterLogsEqualSerialOnTwoThreads) {
  // The whole clip, as `scripts/bench_parallel.sh` times it: blocks that shrink towards the end
  // (81 samples: 13 of 5, then 4, 3, 3, 2, 2, 2), and the rest-pose baseline's DCD computed on a
  // thread of its own while the workers' methods are built. RobotExpressive already intersects
  // itself at rest, so a baseline that came out different would change /frames' baseline and
  // new-finding counts and /events.
  const auto robot = skelcd::test::asset("characters/RobotExpressive.glb").string();
  for (const char* method : {"bvh", "dynamic", "auto"}) {
    SCOPED_TRACE(method);
    const auto log = expect_same_logs(robot, method, {}, std::string("robot-") + method, "2");
    EXPECT_EQ(log.frames.size(), 81u + 80u);
    std::int64_t at_baseline = 0;
    for (const auto& row : log.frames) at_baseline += row.counters.baseline_dcd_pairs;
    EXPECT_GT(at_baseline, 0) << "no finding at the baseline: the baseline proves nothing";
    EXPECT_FALSE(log.events.empty());
  }
}

TEST(ParallelCheck, GeneratedRigLogsEqualSerialExceptTimings) {
  for (const char* method : {"bvh", "dynamic"}) {
    SCOPED_TRACE(method);
    // The rope coils into itself from sample 17 of 24.
    const auto log = expect_same_logs("gen:rope?triangles=200&frames=24", method,
                                      {"--frames", "12:"}, std::string("rope-") + method);
    EXPECT_EQ(log.frames.size(), 12u + 11u);
    EXPECT_GT(log.contacts.size(), 0u);
  }
}

TEST(ParallelCheck, OneIntervalSplitsItsElementaryTestsAndStaysEqual) {
  // One interval (the cloth-funnel step): no blocks to share, so the run is serial across queries
  // and --threads 4 splits each query's elementary tests instead (culling/elementary.hpp). The
  // log must be the serial one; the ground truth says what the CCD must find (27 VF + 107 EE).
  const auto frames = skelcd::test::asset("cloth-funnel/frames").string();
  for (const char* method : {"bvh", "enhanced-dual-cone"}) {
    SCOPED_TRACE(method);
    const auto log = expect_same_logs(frames, method, {}, std::string("funnel-") + method);
    ASSERT_EQ(log.frames.size(), 2u + 1u);
    std::int64_t vf = 0, ee = 0;
    for (const auto& row : log.frames) {
      vf += row.counters.vf_contacts;
      ee += row.counters.ee_contacts;
      if (row.kind == skelcd::tools::QueryKind::ccd) {
        ASSERT_GE(
            static_cast<std::size_t>(row.counters.vf_tests + row.counters.ee_tests),
            skelcd::culling::kParallelElementaryThreshold);  // the split path ran
      }
    }
    EXPECT_EQ(vf, 27);
    EXPECT_EQ(ee, 107);
  }
}

TEST(ParallelCheck, TheComparisonSeesADifferentCounter) {
  // The same comparison between two runs that differ (another method) must fail on /frames:
  // it is not blind.
  const auto dir = skelcd::test::temp_dir("parallel-blind");
  const auto a = (dir / "bvh.h5").string();
  const auto b = (dir / "kdop.h5").string();
  ASSERT_EQ(run_skelcd({"check", kCharacter, "--frames", "40:41", "--method", "bvh", "-o", a})
                .exit_code, 0);
  ASSERT_EQ(run_skelcd({"check", kCharacter, "--frames", "40:41", "--method", "kdop", "-o", b})
                .exit_code, 0);
  const Reader ra = read_all(a);
  const Reader rb = read_all(b);
  ASSERT_TRUE(ra.items.count("/frames") == 1 && rb.items.count("/frames") == 1);
  EXPECT_NE(ra.items.at("/frames"), rb.items.at("/frames"));
  EXPECT_NE(ra.items.at("/@method"), rb.items.at("/@method"));
}

}  // namespace
