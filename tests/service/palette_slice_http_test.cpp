// Integration tests of the palette (Cavagnino & Gribaudo) and slice (Liao)
// modes through the real `voxd serve`: exact choices where the answer is
// known, the exported meshes' volumes, the palette JSON, the colour outputs
// (RLE, .vox, PNG stack, layers, preview, sections) against the engine,
// and clear refusals.
#include <cmath>
#include <cstring>
#include <map>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "support/http_fixture.h"
#include "voxd/voxelize/palette.h"
#include "voxd/voxelize/slice_functions.h"
#include "voxd/encode/volume_format.h"

namespace voxd::test {
namespace {

using nlohmann::json;

using PaletteSliceTest = HttpServiceTest;

std::span<const std::uint8_t> span_of(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

// A right prism over the triangle x, y >= 0, x + y <= 8, z in [0, 4]: its
// slanted face runs along the unit voxels' face diagonals.
Mesh diagonal_prism() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {8, 0, 0}, {0, 8, 0}, {0, 0, 4}, {8, 0, 4}, {0, 8, 4}};
  m.triangles = {{0, 2, 1}, {3, 4, 5}, {0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4}, {2, 0, 3}, {2, 3, 5}};
  return m;
}

// Signed volume enclosed by a binary STL's triangles (divergence theorem).
double stl_volume(const std::string& stl, std::uint32_t* count) {
  EXPECT_GE(stl.size(), 84u);
  std::memcpy(count, stl.data() + 80, 4);
  EXPECT_EQ(stl.size(), 84u + 50u * *count);
  double v = 0;
  for (std::uint32_t t = 0; t < *count; ++t) {
    float f[12];
    std::memcpy(f, stl.data() + 84 + 50 * t, 48);
    const glm::dvec3 a(f[3], f[4], f[5]), b(f[6], f[7], f[8]), c(f[9], f[10], f[11]);
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

TEST_F(PaletteSliceTest, PaletteChoosesWedgesOnDiagonalsAndExportsTheExactVolume) {
  start();
  const std::string params =
      R"({"grid":{"voxel_size":1,"origin":[0,0,0],"dims":[10,10,6]},"mode":"palette",)"
      R"("palette":{"elements":46,"metric":"outer","rays":16,"points":4,"seed":7,)"
      R"("render":{"full":[{"object":"brick"}],"wedge-z-x0y0":[{"object":"slope","min_similarity":0.9},{"object":"brick"}]}}})";
  const std::string id = finished(submit(to_binary_stl(diagonal_prism()), params));
  const json status = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  const json& values = status.at("values");
  EXPECT_EQ(values.at("type"), "u8");
  EXPECT_EQ(values.at("quantity"), "palette element");
  EXPECT_EQ(values.at("palette"), "46");
  EXPECT_EQ(values.at("metric"), "outer");
  EXPECT_EQ(values.at("rays"), 16);
  EXPECT_EQ(values.at("layers"), json({"element", "similarity", "display"}));

  // Independent count: voxel [i, i+1) x [j, j+1) is full when i + j + 2 <= 8,
  // the wedge on the diagonal i + j == 7, for the 4 layers under the top.
  const Palette palette = builtin_palette(46);
  const std::uint8_t full = 1, wedge = static_cast<std::uint8_t>(*palette.find("wedge-z-x0y0"));
  const DenseVolume<std::uint8_t> element = read_rle_u8(span_of(volume(id, "?format=rle")));
  const DenseVolume<std::uint8_t> similarity = read_rle_u8(span_of(volume(id, "?format=rle&layer=similarity")));
  const DenseVolume<std::uint8_t> display = read_rle_u8(span_of(volume(id, "?format=rle&layer=display")));
  EXPECT_EQ(read_rle_u8(span_of(volume(id, "?format=rle&layer=element"))).values(), element.values());
  int fulls = 0, wedges = 0;
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i) {
        const std::uint8_t want = k >= 4 ? 0 : i + j + 2 <= 8 ? full : i + j == 7 ? wedge : 0;
        ASSERT_EQ(element.at(i, j, k), want) << i << "," << j << "," << k;
        ASSERT_EQ(similarity.at(i, j, k), 255);
        // full shows object 1 ("brick"), the exact wedges object 2 ("slope").
        ASSERT_EQ(display.at(i, j, k), want == full ? 1 : want == wedge ? 2 : 0);
        fulls += want == full;
        wedges += want == wedge;
      }
  EXPECT_EQ(fulls, 4 * 28);
  EXPECT_EQ(wedges, 4 * 8);

  // The palette JSON: every element's constraints and volume, the histogram.
  const json p = expect_json(http().Get(("/v1/jobs/" + id + "/palette").c_str()), 200, "PaletteResult");
  ASSERT_EQ(p.at("elements").size(), 46u);
  EXPECT_EQ(p.at("elements").at(wedge).at("name"), "wedge-z-x0y0");
  EXPECT_EQ(p.at("elements").at(wedge).at("pieces"), json::parse("[[[1.0,1.0,0.0,1.0]]]"));
  EXPECT_NEAR(p.at("elements").at(wedge).at("volume").get<double>(), 0.5, 1e-12);
  EXPECT_EQ(p.at("elements").at(full).at("voxels"), fulls);
  EXPECT_EQ(p.at("elements").at(wedge).at("voxels"), wedges);
  EXPECT_EQ(p.at("elements").at(0).at("voxels"), 600 - fulls - wedges);
  for (const json& e : p.at("elements")) {
    const std::string name = e.at("name");
    const double v = e.at("volume");
    if (name.starts_with("tetra-")) {
      EXPECT_NEAR(v, 1.0 / 6, 1e-12) << name;
    } else if (name.starts_with("pyramid-")) {
      EXPECT_NEAR(v, 1.0 / 3, 1e-12) << name;
    }
  }
  EXPECT_EQ(p.at("render").at("objects").at(0).at("name"), "brick");
  EXPECT_EQ(p.at("render").at("objects").at(0).at("voxels"), fulls);
  EXPECT_EQ(p.at("render").at("objects").at(1).at("voxels"), wedges);
  EXPECT_EQ(p.at("render").at("nothing_shown"), 600 - fulls - wedges);

  // The reconstruction as STL encloses exactly the prism (32 x 4).
  auto res = http().Get(("/v1/jobs/" + id + "/volume?format=stl").c_str());
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "model/stl");
  std::uint32_t triangles = 0;
  EXPECT_NEAR(stl_volume(res->body, &triangles), 128.0, 1e-3);
  EXPECT_GT(triangles, 0u);
  // The synchronous route streams the same mesh.
  res = post_multipart(http(), "/v1/voxelize?format=stl", to_binary_stl(diagonal_prism()), "p.stl", params);
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_NEAR(stl_volume(res->body, &triangles), 128.0, 1e-3);
  // glb: one instanced mesh per element used.
  res = http().Get(("/v1/jobs/" + id + "/volume?format=glb").c_str());
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "model/gltf-binary");
  ASSERT_GT(res->body.size(), 20u);
  EXPECT_EQ(res->body.substr(0, 4), "glTF");
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, res->body.data() + 12, 4);
  const json gltf = json::parse(res->body.substr(20, json_length));
  EXPECT_EQ(gltf.at("extensionsUsed"), json({"EXT_mesh_gpu_instancing"}));
  EXPECT_EQ(gltf.at("extensionsRequired"), json({"EXT_mesh_gpu_instancing"}));
  EXPECT_EQ(gltf.at("meshes").size(), 2u);  // full and the wedge

  // Refusals: colour formats, a layer of another kind, palette routes of other modes.
  json problem = expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=vox").c_str()), 400, "invalid-query");
  EXPECT_NE(problem.at("detail").get<std::string>().find("vox holds colours"), std::string::npos) << problem.dump();
  problem = expect_problem(http().Get(("/v1/jobs/" + id + "/volume?layer=depth").c_str()), 400, "invalid-query");
  EXPECT_NE(problem.at("detail").get<std::string>().find("element, similarity or display"), std::string::npos);
  const std::string solid = finished(submit(to_binary_stl(diagonal_prism()), R"({"grid":{"resolution":8}})"));
  problem = expect_problem(http().Get(("/v1/jobs/" + solid + "/palette").c_str()), 409, "wrong-mode");
  EXPECT_NE(problem.at("detail").get<std::string>().find("\"mode\": \"palette\""), std::string::npos) << problem.dump();
  // A solid's glb is its voxel surface (surface_mesh_http_test), not a reconstruction.
  const auto solid_glb = http().Get(("/v1/jobs/" + solid + "/volume?format=glb").c_str());
  ASSERT_TRUE(solid_glb);
  EXPECT_EQ(solid_glb->status, 200);
  EXPECT_EQ(solid_glb->get_header_value("Content-Type"), "model/gltf-binary");
  problem = expect_problem(http().Get(("/v1/jobs/" + solid + "/volume?layer=similarity").c_str()), 400, "invalid-query");

  // Element and similarity survive a restart.
  ASSERT_EQ(server_->stop(), 0);
  start();
  EXPECT_EQ(read_rle_u8(span_of(volume(id, "?format=rle"))).values(), element.values());
  EXPECT_EQ(read_rle_u8(span_of(volume(id, "?format=rle&layer=similarity"))).values(), similarity.values());
}

TEST_F(PaletteSliceTest, AnisotropicVoxelsExportInModelUnits) {
  start();
  // Voxels 1 x 1 x 0.5: the prism's 4 units of height take 8 layers.
  const std::string id = finished(submit(
      to_binary_stl(diagonal_prism()),
      R"({"grid":{"voxel_size":1},"mode":"palette","palette":{"elements":10,"voxel_aspect":[1,1,0.5]}})"));
  const json status = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  EXPECT_EQ(status.at("grid").at("dims"), json({8, 8, 8})) << status.dump();
  EXPECT_EQ(status.at("values").at("voxel_edges"), json({1.0, 1.0, 0.5}));
  std::uint32_t triangles = 0;
  const double v = stl_volume(volume(id, "?format=stl"), &triangles);
  // The staircase of the 10-element palette (no wedges) around the prism's
  // 128: full voxels inside, tetrahedra or nothing on the diagonal.
  EXPECT_GT(v, 112.0);
  EXPECT_LT(v, 144.0);
}

TEST_F(PaletteSliceTest, PaletteJobJsonErrorsPointAtTheField) {
  start();
  const auto errors = [&](const std::string& params) {
    return expect_problem(post_multipart(http(), "/v1/jobs", to_binary_stl(diagonal_prism()), "p.stl", params), 422,
                          "invalid-params")
        .at("errors");
  };
  json e = errors(R"({"mode":"palette","palette":{"elements":45}})");
  EXPECT_EQ(e.at(0).at("path"), "/palette/elements");
  EXPECT_NE(e.at(0).at("message").get<std::string>().find("2, 10, 46 or 78"), std::string::npos);
  e = errors(R"({"mode":"palette","palette":{"metric":"best","rays":0}})");
  EXPECT_EQ(e.size(), 2u);
  e = errors(R"({"mode":"palette","palette":{"render":{"wedge":[{"object":"x"}]}}})");
  EXPECT_EQ(e.at(0).at("path"), "/palette/render/wedge");
  e = errors(R"({"mode":"palette","palette":{"elements":[{"name":"a","pieces":[[[0,0,0,1]]]}]}})");
  EXPECT_EQ(e.at(0).at("path"), "/palette/elements/0/pieces/0/0");
  e = errors(R"({"mode":"palette","inside":"winding"})");
  EXPECT_EQ(e.at(0).at("path"), "/inside");
  e = errors(R"({"mode":"slice"})");
  EXPECT_EQ(e.at(0).at("path"), "/slice");
  e = errors(R"({"mode":"slice","slice":{"function":"marble","color":[1,2,3]}})");
  EXPECT_EQ(e.at(0).at("path"), "/slice/color");
  EXPECT_NE(e.at(0).at("message").get<std::string>().find("single_color"), std::string::npos);
  e = errors(R"({"mode":"slice","slice":{"function":"single_color","color":[1,2,3,0]}})");
  EXPECT_NE(e.at(0).at("message").get<std::string>().find("alpha 0"), std::string::npos);
  e = errors(R"({"mode":"slice","slice":{"function":"color_ramp","ramp":[{"position":0.5,"color":"#ff0000"},{"position":0.2,"color":"#00ff00"}]}})");
  EXPECT_EQ(e.at(0).at("path"), "/slice/ramp/1/position");
  e = errors(R"({"mode":"slice","slice":{"function":"custom"}})");
  EXPECT_EQ(e.at(0).at("path"), "/slice/lookup");
  e = errors(R"({"mode":"slice","slice":{"function":"custom","lookup":{"dims":[2,1,1],"colors":["#ff0000"]}}})");
  EXPECT_EQ(e.at(0).at("path"), "/slice/lookup/colors");
  e = errors(R"({"mode":"solid","slice":{"function":"rock"}})");
  EXPECT_EQ(e.at(0).at("path"), "/slice");
}

TEST_F(PaletteSliceTest, SliceColoursEveryFormatAndImageAlike) {
  start();
  const Mesh box = make_box({0.5, 0.5, 0.5}, {6.5, 5.5, 4.5});
  const std::string params =
      R"({"grid":{"voxel_size":0.5,"origin":[0,0,0],"dims":[14,12,10]},"mode":"slice",)"
      R"("slice":{"function":"color_ramp","axis":[0,0,1],"ramp":[{"position":0,"color":"#0000ff"},{"position":1,"color":[255,0,0]}]}})";
  const std::string id = finished(submit(to_binary_stl(box), params));
  const json status = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  EXPECT_EQ(status.at("values").at("type"), "rgba8");
  EXPECT_EQ(status.at("values").at("function"), "color_ramp");
  EXPECT_EQ(status.at("filled_voxels"), 12 * 10 * 8);

  // The service's colours are the engine's, voxel for voxel; alpha > 0 is the solid.
  SliceOptions o;
  o.function = SliceFunction::color_ramp;
  o.ramp = {{0.0, {0, 0, 255, 255}}, {1.0, {255, 0, 0, 255}}};
  Grid grid;
  grid.voxel_size = 0.5;
  grid.dims = {14, 12, 10};
  const DenseVolume<Rgba8> expected = voxelize_slice(box, grid, o);
  const DenseVolume<Rgba8> colours = read_rle_rgba8(span_of(volume(id, "?format=rle")));
  ASSERT_EQ(colours.values(), expected.values());
  const std::string raw = volume(id, "?format=raw");
  ASSERT_EQ(raw.size(), 14u * 12 * 10 * 4);
  EXPECT_EQ(std::memcmp(raw.data(), colours.values().data(), raw.size()), 0);

  // .vox: one model, every filled voxel once.
  const std::string vox = volume(id, "?format=vox");
  EXPECT_EQ(vox.substr(0, 4), "VOX ");
  const std::size_t xyzi = vox.find("XYZI");
  ASSERT_NE(xyzi, std::string::npos);
  std::uint32_t voxels = 0;
  std::memcpy(&voxels, vox.data() + xyzi + 12, 4);
  EXPECT_EQ(voxels, 12u * 10 * 8);

  // The PNG stack: a manifest and one PNG per layer; a layer by its URL is the zip's entry.
  write_file(dir_ + "/stack.zip", bytes_of(volume(id, "?format=png-stack")));
  const auto listing = run_process("/usr/bin/python3 -c \"import zipfile,sys; z=zipfile.ZipFile(sys.argv[1]); "
                                   "assert z.testzip() is None; print(len(z.namelist())); "
                                   "sys.stdout.flush(); open(sys.argv[2],'wb').write(z.read('layer-00003.png'))\" " +
                                   dir_ + "/stack.zip " + dir_ + "/layer3.png");
  ASSERT_EQ(listing.exit_code, 0) << listing.err;
  EXPECT_EQ(listing.out, "11\n");
  auto res = http().Get(("/v1/jobs/" + id + "/layers/3").c_str());
  ASSERT_EQ(res->status, 200);
  EXPECT_EQ(res->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(bytes_of(res->body), read_file(dir_ + "/layer3.png"));
  const json layer = read_png(res->body);
  EXPECT_EQ(layer.at("width"), 14);
  EXPECT_EQ(layer.at("color_type"), 6);  // RGBA
  expect_problem(http().Get(("/v1/jobs/" + id + "/layers/10").c_str()), 404, "not-found");

  // The preview shows the colours: seen from +z, the part is its top layer,
  // the reddest of the ramp.
  const json top = read_png(http().Get(("/v1/jobs/" + id + "/preview?view=%2Bz").c_str())->body);
  const auto& px = top.at("pixels");
  const int w = top.at("width");
  const std::size_t centre = 3 * static_cast<std::size_t>(6 * w + 7);
  EXPECT_GT(px.at(centre).get<int>(), 100) << "red";
  EXPECT_LT(px.at(centre + 2).get<int>(), px.at(centre).get<int>()) << "more red than blue";
  // A section at z layer 3 shows layer 3's colours over white.
  const json section = read_png(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=3").c_str())->body);
  const Rgba8 c = colours.at(5, 5, 3);
  const std::size_t at = 3 * static_cast<std::size_t>(5 * 14 + 5);
  EXPECT_EQ(section.at("pixels").at(at), c.r);
  EXPECT_EQ(section.at("pixels").at(at + 1), c.g);
  EXPECT_EQ(section.at("pixels").at(at + 2), c.b);
  EXPECT_EQ(section.at("pixels").at(0), 255);  // empty: white

  // Refusals: formats without colours, palette routes.
  json p = expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=nrrd").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("rle, raw, vox or png-stack"), std::string::npos);
  expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=stl").c_str()), 400, "invalid-query");
  expect_problem(http().Get(("/v1/jobs/" + id + "/palette").c_str()), 409, "wrong-mode");
  const std::string solid = finished(submit(to_binary_stl(box), R"({"grid":{"resolution":8}})"));
  expect_problem(http().Get(("/v1/jobs/" + solid + "/layers/0").c_str()), 409, "wrong-mode");
  p = expect_problem(http().Get(("/v1/jobs/" + solid + "/volume?format=png-stack").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("holds colours"), std::string::npos);
}

}  // namespace
}  // namespace voxd::test
