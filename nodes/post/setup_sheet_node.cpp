#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/io/write_support.h"
#include "nodes/post/setup_sheet.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {

NodeDecl make_setup_sheet_node() {
  NodeDecl d;
  d.type = "post.setup_sheet";
  d.version = 3;  // 2: a setup added for rest passes is named as cutting only what the others leave; 3: how far above a pass start the rapids come down
  d.description =
      "the setup sheet a machinist reads: the clampings in order, how to clamp (which direction up, which side "
      "down), work zero, the program, what it cuts, the certificate's verdict, a picture per setup (Markdown)";
  d.cache_on_disk = false;  // it writes files
  d.input("programs", "SetupPaths", "the programs in cutting order (post.setup_programs)")
      .input("setups", "Report", "surface.setups' report: each setup's axis and patches")
      .input("surfaces", "Mesh", "the patches as a mesh, face label = patch (surface.fit_bspline): the pictures")
      .input("certificate", "Report", "post.simulate_part's report: its verdict and per setup figures", false)
      .output("file", "File", "the setup sheet")
      .param_output_path("path", "the sheet to write (Markdown), relative to the output folder (-o); its pictures "
                                 "(setup_1.png, ...) go beside it")
      .param_int("width", 800, 200, 4000, "px", "width of each setup's picture");
  d.run = [](NodeContext& ctx) {
    auto programs = ctx.input<SetupPaths>("programs");
    auto surfaces = ctx.input<Mesh>("surfaces");
    const std::string param = ctx.text("path");
    if (param.empty()) throw NodeError("parameter 'path' is empty: give the setup sheet to write");
    std::size_t patches = 0;
    for (int label : surfaces->face_label) patches = std::max<std::size_t>(patches, label + 1);
    SetupSheet sheet;
    try {
      // without labels (no pictures) the patch indices cannot be checked against the surfaces
      const auto setups = setups_from_report(ctx.input<Report>("setups")->data,
                                             surfaces->has_labels() ? patches : SIZE_MAX);
      std::shared_ptr<const Report> certificate;
      if (ctx.has_input("certificate")) certificate = ctx.input<Report>("certificate");
      sheet = setup_sheet(*programs, setups, *surfaces, certificate ? &certificate->data : nullptr,
                          static_cast<int>(ctx.integer("width")));
    } catch (const std::invalid_argument& e) {
      throw NodeError(std::string("post.setup_sheet: ") + e.what());
    }
    ctx.set("file", io::write_output_files(ctx, param, sheet.markdown, sheet.pictures));
  };
  return d;
}

}  // namespace scallop::post_nodes
