#include <memory>
#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/geom/point_text.h"
#include "nodes/surface/setups.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"
#include "nodes/types/surfaces.h"

namespace scallop::surface_nodes {

NodeDecl make_setups_node() {
  NodeDecl d;
  d.type = "surface.setups";
  d.version = 7;  // 7: the hidden patches told in one line, the most hidden named; 2: the part hides patches from axes; 3: square axes win ties within 0.005; 4: hidden patches reached around the part; 5: hidden_patches; 6: normals held within the patch's cap
  d.description =
      "groups the patches into clampings by machining direction, as few as the directions allow (greedy set cover), "
      "each with the rigid transform from the part's frame to the machine's (tool axis +z); a patch the part hides from "
      "its own direction (a bore's wall) is reached from the direction that sees most of it (from the bore's end)";
  d.input("surfaces", "Surfaces", "the patches (surface.fit_bspline)")
      .input("mesh", "Mesh",
             "the whole part: an axis reaches a patch only where the part does not hide it, and the part is placed "
             "in each setup (centred on x = y = 0, lowest point z = 0)",
             false)
      .output("report", "Report",
              "{setups: [{name, axis (part frame, towards the spindle), part_to_machine (3 x 4 [R|t], as "
              "scallop-setups/1), patches, min_normal_dot, hidden_samples, hidden_patches: [{patch, samples (of 289 "
              "per patch), at (their mean, part frame)}]}], patches (count), min_normal_dot (the option)}");
  d.options<SetupOptions>().number("min_normal_dot", &SetupOptions::min_normal_dot, 1e-6, 1, "",
                                   "a setup cuts a patch when n . axis is at least this over it (0.2: walls up to "
                                   "about 78 degrees), or when the axis is the patch's own direction")
      .flag("any_axis", &SetupOptions::any_axis,
            "also axes at compound angles (2000 over the sphere): fewer setups, for a fixture that tilts the part; "
            "otherwise the patches' own directions, the coordinate axes and the one away from the base");
  d.run = [](NodeContext& ctx) {
    auto surfaces = ctx.input<Surfaces>("surfaces");
    const std::shared_ptr<const Mesh> part =
        ctx.has_input("mesh") ? ctx.input<Mesh>("mesh") : std::make_shared<const Mesh>();
    const SetupOptions o = ctx.options<SetupOptions>();
    std::vector<Setup> setups;
    try {
      setups = plan_setups(*surfaces, *part, o);
    } catch (const std::invalid_argument& e) {
      throw NodeError(std::string("surface.setups: ") + e.what());
    }
    // One line however many setups it concerns (the face bust's 22 setups: 8 lines), the most
    // hidden patch named, every one in the report.
    std::size_t hidden = 0;
    const Setup* worst_setup = nullptr;
    const HiddenPatch* worst = nullptr;
    for (const Setup& st : setups)
      for (const HiddenPatch& h : st.hidden_patches) {
        ++hidden;
        if (!worst || h.samples > worst->samples) worst = &h, worst_setup = &st;
      }
    if (worst) {
      const std::string most = "setup '" + worst_setup->name + "': the part hides " + std::to_string(worst->samples) +
                               " of 289 samples of patch " + std::to_string(worst->patch) + " from this axis (around " +
                               point_text(worst->at, 2) + ", part frame)";
      ctx.warn(hidden == 1 ? most + ": the ball does not reach those places from this clamping, they are left as stock"
                           : std::to_string(hidden) + " patches are partly hidden by the part from the axis of a setup "
                             "that cuts them (the most, " + most + "; the report's hidden_patches per setup): the "
                             "ball does not reach those places from that clamping, they are left as stock");
    }
    Report report;
    report.data = {{"setups", setups_report(setups)}, {"patches", surfaces->patches.size()}, {"min_normal_dot", o.min_normal_dot}};
    ctx.set("report", std::move(report));
  };
  return d;
}

}  // namespace scallop::surface_nodes
