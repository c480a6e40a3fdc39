// The "device" job parameter and `--device` flags through the real voxd,
// with every GPU hidden from it (CUDA_VISIBLE_DEVICES=""), so the answers
// are those of a machine without one wherever the test runs: auto runs a
// slice job on the CPU with the bytes of device cpu and says so, cuda is
// refused before any work with what to use instead, a mode that runs only
// on the CPU refuses cuda at its field, `serve --device cuda` does not
// start, and `voxd devices` says why there is no GPU.
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "support/http_fixture.h"
#include "voxd/compute_device.h"

namespace voxd::test {
namespace {

using nlohmann::json;

const std::vector<std::string> kNoGpu = {"CUDA_VISIBLE_DEVICES="};
// This process too, before anything asks CUDA, so the reasons it expects
// are those the hidden voxd gives on a GPU machine as well.
const bool kGpusHidden = setenv("CUDA_VISIBLE_DEVICES", "", 1) == 0;

class ComputeDeviceTest : public HttpServiceTest {};

std::string slice_job(const std::string& device) {
  return R"({"grid":{"resolution":130},"mode":"slice","slice":{"function":"marble","period":0.7,"noise_scale":0.3},)"
         R"("device":")" + device + R"("})";
}

TEST_F(ComputeDeviceTest, AutoRunsOnTheCpuWithTheSameBytesAndSaysWhere) {
  start({}, kNoGpu);
  const auto mesh = to_binary_stl(make_torus({0, 0, 0}, 1.0, 0.45, 40, 20));
  const std::string automatic = finished(submit(mesh, slice_job("auto")));
  const std::string cpu = finished(submit(mesh, slice_job("cpu")));
  const json status = expect_json(http().Get(("/v1/jobs/" + automatic).c_str()), 200, "JobStatus");
  EXPECT_EQ(status.at("values").at("device"), "cpu");
  EXPECT_EQ(status.at("params").at("device"), "auto");
  const std::string bytes = volume(automatic, "?format=raw");
  EXPECT_GT(bytes.size(), 130u * 130 * 4);
  EXPECT_TRUE(bytes == volume(cpu, "?format=raw"));
}

// Coverage takes a device too: auto, past the 2^21 voxels where a GPU
// would take it, gives the CPU's bytes and says so; cuda is refused at
// admission.
TEST_F(ComputeDeviceTest, CoverageAutoRunsOnTheCpuAndCudaIsRefused) {
  start({}, kNoGpu);
  const auto mesh = to_binary_stl(make_torus({0, 0, 0}, 1.0, 0.45, 40, 20));
  const auto coverage_job = [](const std::string& device) {
    return R"({"grid":{"resolution":200},"mode":"coverage","coverage":{"rays":2},"device":")" + device + R"("})";
  };
  const std::string automatic = finished(submit(mesh, coverage_job("auto")));
  const std::string cpu = finished(submit(mesh, coverage_job("cpu")));
  const json status = expect_json(http().Get(("/v1/jobs/" + automatic).c_str()), 200, "JobStatus");
  EXPECT_EQ(status.at("values").at("device"), "cpu");
  EXPECT_EQ(status.at("values").at("quantity"), "coverage");
  const std::string bytes = volume(automatic, "?format=raw");
  EXPECT_GE(bytes.size(), std::size_t{1} << 21);
  EXPECT_TRUE(bytes == volume(cpu, "?format=raw"));
  const json p = expect_problem(post_multipart(http(), "/v1/jobs", mesh, "part.stl", coverage_job("cuda")), 422,
                                "invalid-params");
  EXPECT_NE(std::string(p.at("detail")).find("use device auto or cpu"), std::string::npos) << p.dump();
}

// So does sdf: auto's band is the CPU's here, the same floats as cpu's,
// and values.device says so, streamed or not.
TEST_F(ComputeDeviceTest, SdfAutoRunsOnTheCpuWithTheSameFloatsAndSaysWhere) {
  start({}, kNoGpu);
  const auto mesh = to_binary_stl(make_torus({0, 0, 0}, 1.0, 0.45, 40, 20));
  const auto sdf_job = [](const std::string& device, const std::string& streaming) {
    return R"({"grid":{"resolution":200},"mode":"sdf","sdf":{"band":2},"streaming":")" + streaming +
           R"(","device":")" + device + R"("})";
  };
  const std::string automatic = finished(submit(mesh, sdf_job("auto", "off")));
  const std::string cpu = finished(submit(mesh, sdf_job("cpu", "off")));
  const std::string streamed = finished(submit(mesh, sdf_job("auto", "on")));
  for (const std::string& id : {automatic, streamed}) {
    const json status = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
    EXPECT_EQ(status.at("values").at("device"), "cpu") << status.dump();
    EXPECT_EQ(status.at("values").at("quantity"), "signed distance");
  }
  const std::string bytes = volume(automatic, "?format=raw");
  EXPECT_GE(bytes.size(), std::size_t{4} << 21);
  EXPECT_TRUE(bytes == volume(cpu, "?format=raw"));
  EXPECT_TRUE(bytes == volume(streamed, "?format=raw"));
}

TEST_F(ComputeDeviceTest, CudaWithoutAGpuIsRefusedSayingWhatToUse) {
  start({}, kNoGpu);
  const auto mesh = to_binary_stl(make_torus({0, 0, 0}, 1.0, 0.45, 24, 12));
  const json p = expect_problem(post_multipart(http(), "/v1/jobs", mesh, "part.stl", slice_job("cuda")), 422,
                                "invalid-params");
  const std::string detail = p.at("detail");
  EXPECT_NE(detail.find(cuda_built() ? "device cuda: no usable CUDA GPU on this machine"
                                     : "device cuda: this voxd was built without its CUDA backend"),
            std::string::npos)
      << detail;
  EXPECT_NE(detail.find("use device auto or cpu"), std::string::npos) << detail;
  // Refused at admission: no job was queued.
  const json jobs = expect_json(http().Get("/v1/jobs"), 200, "JobList");
  EXPECT_TRUE(jobs.at("jobs").empty()) << jobs.dump();
}

TEST_F(ComputeDeviceTest, AModeThatRunsOnlyOnTheCpuRefusesCudaAtItsField) {
  start({}, kNoGpu);
  const auto mesh = to_binary_stl(make_torus({0, 0, 0}, 1.0, 0.45, 24, 12));
  const json p = expect_problem(post_multipart(http(), "/v1/jobs", mesh, "part.stl",
                                               R"({"grid":{"resolution":20},"mode":"palette","device":"cuda"})"),
                                422, "invalid-params");
  ASSERT_TRUE(p.contains("errors")) << p.dump();
  EXPECT_EQ(p.at("errors").at(0).at("path"), "/device");
  EXPECT_EQ(p.at("errors").at(0).at("message"),
            R"(mode "palette" runs only on the CPU; drop "device" or use auto or cpu)");
  expect_problem(post_multipart(http(), "/v1/jobs", mesh, "part.stl", R"({"mode":"slice","slice":{"function":"rock"},"device":"gpu"})"),
                 422, "invalid-params");
}

TEST_F(ComputeDeviceTest, ServeWithDeviceCudaDoesNotStartWithoutAGpu) {
  const ProcessResult r = run_process("CUDA_VISIBLE_DEVICES= " + std::string(VOXD_BINARY) +
                                      " serve --port 0 --device cuda --data-dir " + dir_ + "/never");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--device: device cuda: "), std::string::npos) << r.err;
  const ProcessResult cli = run_process("CUDA_VISIBLE_DEVICES= " + std::string(VOXD_BINARY) + " voxelize " +
                                        std::string(VOXD_TEST_PARTS) + "/torus.stl -o " + dir_ +
                                        "/t.raw --mode slice --params '{\"slice\":{\"function\":\"wood\"}}' --device cuda");
  EXPECT_EQ(cli.exit_code, 2) << cli.err;
  EXPECT_NE(cli.err.find("device cuda: "), std::string::npos) << cli.err;
  EXPECT_NE(cli.err.find("use device auto or cpu"), std::string::npos) << cli.err;
}

TEST_F(ComputeDeviceTest, DevicesListsNoGpuAndSaysWhy) {
  ASSERT_TRUE(kGpusHidden);
  const ProcessResult r = run_process("CUDA_VISIBLE_DEVICES= " + std::string(VOXD_BINARY) + " devices --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json d = json::parse(r.out);
  EXPECT_EQ(d.at("cuda_built"), cuda_built());
  EXPECT_TRUE(d.at("gpus").empty());
  EXPECT_EQ(d.at("cuda_unavailable"), cuda_unavailable_reason());
  const ProcessResult text = run_process("CUDA_VISIBLE_DEVICES= " + std::string(VOXD_BINARY) + " devices");
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_EQ(text.out, "cpu: yes\ncuda: none (" + cuda_unavailable_reason() + ")\n");
}

}  // namespace
}  // namespace voxd::test
