#include "nodes/io/write_step.h"

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <StepData_StepModel.hxx>
#include <StepShape_AdvancedFace.hxx>
#include <ShapeAnalysis_FreeBounds.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>

#include <mutex>
#include <stdexcept>
#include <vector>

namespace scallop {

namespace {

// OpenCASCADE's STEP translator prints its transfer statistics to stdout, between scallop's own
// progress lines; only its failures are kept (they are reported through our errors anyway).
void quiet_opencascade() {
  static std::once_flag once;
  std::call_once(once, [] {
    const Message_SequenceOfPrinters& printers = Message::DefaultMessenger()->Printers();
    for (Message_SequenceOfPrinters::Iterator p(printers); p.More(); p.Next()) p.Value()->SetTraceLevel(Message_Fail);
  });
}

// OpenCASCADE keeps distinct knots with multiplicities, not the flat vector.
void distinct_knots(const std::vector<double>& flat, std::vector<double>& knots, std::vector<int>& mults) {
  for (double k : flat) {
    if (!knots.empty() && k == knots.back())
      ++mults.back();
    else
      knots.push_back(k), mults.push_back(1);
  }
}

Handle(Geom_BSplineSurface) to_occt(const BSplineSurface& s) {
  std::vector<double> ku, kv;
  std::vector<int> mu, mv;
  distinct_knots(s.knots_u, ku, mu);
  distinct_knots(s.knots_v, kv, mv);
  TColgp_Array2OfPnt poles(1, int(s.poles_u), 1, int(s.poles_v));
  for (std::uint32_t j = 0; j < s.poles_v; ++j)
    for (std::uint32_t i = 0; i < s.poles_u; ++i) {
      const Eigen::Vector3d& p = s.pole(i, j);
      poles(int(i) + 1, int(j) + 1) = gp_Pnt(p.x(), p.y(), p.z());
    }
  TColStd_Array1OfReal uk(1, int(ku.size())), vk(1, int(kv.size()));
  TColStd_Array1OfInteger um(1, int(mu.size())), vm(1, int(mv.size()));
  for (std::size_t k = 0; k < ku.size(); ++k) uk(int(k) + 1) = ku[k], um(int(k) + 1) = mu[k];
  for (std::size_t k = 0; k < kv.size(); ++k) vk(int(k) + 1) = kv[k], vm(int(k) + 1) = mv[k];
  return new Geom_BSplineSurface(poles, uk, vk, um, vm, s.degree_u, s.degree_v);
}

}  // namespace

void write_step(const Surfaces& surfaces, const std::string& path, const WriteStepOptions& options) {
  BRep_Builder builder;
  TopoDS_Compound faces;
  builder.MakeCompound(faces);
  BRepBuilderAPI_Sewing sewing(options.sewing_tolerance);
  for (std::size_t p = 0; p < surfaces.patches.size(); ++p) {
    const std::string problem = bspline_problem(surfaces.patches[p].surface);
    if (!problem.empty()) throw std::runtime_error("patch " + std::to_string(p) + ": " + problem);
    try {
      BRepBuilderAPI_MakeFace face(to_occt(surfaces.patches[p].surface), 1e-7);
      if (!face.IsDone()) throw std::runtime_error("OpenCASCADE made no face of it");
      builder.Add(faces, face.Face());
      sewing.Add(face.Face());
    } catch (const Standard_Failure& e) {
      throw std::runtime_error("patch " + std::to_string(p) + ": OpenCASCADE refused its surface: " +
                               e.GetMessageString());
    }
  }
  TopoDS_Shape shape = faces;
  if (options.sew && surfaces.patches.size() > 1) {
    sewing.Perform();
    shape = sewing.SewedShape();
  }
  quiet_opencascade();
  STEPControl_Writer writer;
  Interface_Static::SetCVal("write.step.unit", "MM");
  Interface_Static::SetCVal("write.step.schema", "AP214IS");
  if (writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone)
    throw std::runtime_error("OpenCASCADE could not translate the surfaces to STEP");
  if (writer.Write(path.c_str()) != IFSelect_RetDone) throw std::runtime_error("cannot write '" + path + "'");
}

StepSummary read_step_summary(const std::string& path) {
  quiet_opencascade();
  STEPControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) throw std::runtime_error("cannot read STEP file '" + path + "'");
  StepSummary s;
  const Handle(StepData_StepModel) model = reader.StepModel();
  for (int e = 1; e <= model->NbEntities(); ++e)
    s.file_faces += model->Value(e)->IsKind(STANDARD_TYPE(StepShape_AdvancedFace));
  reader.TransferRoots();
  const TopoDS_Shape shape = reader.OneShape();
  // Each face and shell once, however often the shape's structure reaches it.
  TopTools_IndexedMapOfShape shells, faces;
  TopExp::MapShapes(shape, TopAbs_SHELL, shells);
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  s.shells = std::size_t(shells.Extent());
  for (int k = 1; k <= faces.Extent(); ++k) {
    ++s.faces;
    const GeomAdaptor_Surface a(BRep_Tool::Surface(TopoDS::Face(faces(k))));
    s.bspline_faces += a.GetType() == GeomAbs_BSplineSurface;
  }
  ShapeAnalysis_FreeBounds bounds(shape);
  for (TopExp_Explorer e(bounds.GetClosedWires(), TopAbs_EDGE); e.More(); e.Next()) ++s.free_edges;
  for (TopExp_Explorer e(bounds.GetOpenWires(), TopAbs_EDGE); e.More(); e.Next()) ++s.free_edges;
  return s;
}

}  // namespace scallop
