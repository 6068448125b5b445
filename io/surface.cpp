// Closed surfaces read with VTK and checked before the lattice is filled (io/surface.hpp): STL and OBJ files in
// 3D, polygons in 2D.
#include "io/surface.hpp"

#include <fmt/format.h>

#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCleanPolyData.h>
#include <vtkCommand.h>
#include <vtkExecutive.h>
#include <vtkFeatureEdges.h>
#include <vtkImplicitPolyDataDistance.h>
#include <vtkLine.h>
#include <vtkNew.h>
#include <vtkOBJReader.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolygon.h>
#include <vtkSTLReader.h>
#include <vtkSmartPointer.h>
#include <vtkTriangleFilter.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_set>

namespace mpsfsi {

namespace fs = std::filesystem;

struct ClosedSurface::Impl {
  // 3D: the triangles and VTK's signed distance (angle-weighted pseudonormals at edges and vertices).
  vtkSmartPointer<vtkPolyData> mesh;
  vtkSmartPointer<vtkImplicitPolyDataDistance> distance;
  // 2D: the polygon's points, each as x, y, 0 (VTK's layout), and its bounds as VTK wants them.
  std::vector<double> polygon;
  double polygon_bounds[6] = {0, 0, 0, 0, 0, 0};
};

ClosedSurface::ClosedSurface() : impl_(std::make_unique<Impl>()) {}
ClosedSurface::~ClosedSurface() = default;

Vec SurfaceTransform::apply(const Vec& x) const {
  const Vec scaled = scale.cwiseProduct(x);
  const Real to_rad = pi / 180;
#if MPSFSI_DIM == 2
  return Eigen::Rotation2D<Real>(rotate_deg[0] * to_rad).toRotationMatrix() * scaled + translate;
#else
  {
    const Eigen::Matrix<Real, 3, 3> r = (Eigen::AngleAxis<Real>(rotate_deg[2] * to_rad, Eigen::Matrix<Real, 3, 1>::UnitZ()) *
                                         Eigen::AngleAxis<Real>(rotate_deg[1] * to_rad, Eigen::Matrix<Real, 3, 1>::UnitY()) *
                                         Eigen::AngleAxis<Real>(rotate_deg[0] * to_rad, Eigen::Matrix<Real, 3, 1>::UnitX()))
                                            .toRotationMatrix();
    Eigen::Matrix<Real, 3, 1> y;
    for (int a = 0; a < 3; ++a) y[a] = scaled[a];
    y = r * y;
    Vec out;
    for (int a = 0; a < dim; ++a) out[a] = y[a];
    return out + translate;
  }
#endif
}

namespace {

/// Records the first error and the first warning a VTK reader reports instead of printing them: the text after
/// VTK's "ERROR: In <source>, line N\n<class> (<address>): ".
struct VtkErrors {
  std::string error, warning;
  vtkNew<vtkCallbackCommand> command;
  /// The first error, else the first warning; empty when there was neither.
  std::string first() const { return error.empty() ? warning : error; }
  explicit VtkErrors(vtkObject* watched) {
    command->SetClientData(this);
    command->SetCallback([](vtkObject*, const unsigned long event, void* client, void* call) {
      auto* self = static_cast<VtkErrors*>(client);
      std::string& slot = event == vtkCommand::ErrorEvent ? self->error : self->warning;
      if (!slot.empty() || !call) return;
      std::string text = static_cast<const char*>(call);
      const auto line_end = text.find('\n');
      const auto from = text.find("): ", line_end == std::string::npos ? 0 : line_end);
      if (from != std::string::npos) text = text.substr(from + 3);
      while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
      slot = text;
    });
    watched->AddObserver(vtkCommand::ErrorEvent, command);
    watched->AddObserver(vtkCommand::WarningEvent, command);
  }
  /// The algorithm's errors and its executive's (which reports the algorithm's failure once more).
  explicit VtkErrors(vtkAlgorithm* algorithm) : VtkErrors(static_cast<vtkObject*>(algorithm)) {
    algorithm->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, command);
    algorithm->GetExecutive()->AddObserver(vtkCommand::WarningEvent, command);
  }
};

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

/// The triangles of an STL or OBJ file, with coincident points merged and degenerate triangles dropped.
vtkSmartPointer<vtkPolyData> read_mesh(const std::string& path) {
  const std::string ext = lower_extension(path);
  vtkSmartPointer<vtkAbstractPolyDataReader> reader;
  if (ext == ".stl") reader = vtkSmartPointer<vtkSTLReader>::New();
  else if (ext == ".obj") reader = vtkSmartPointer<vtkOBJReader>::New();
  else throw SurfaceError(fmt::format("'{}' is not an .stl or .obj file; expected a surface in STL or OBJ format", path));
  VtkErrors errors(reader);
  reader->SetFileName(path.c_str());
  reader->Update();
  if (!errors.error.empty() || (!errors.warning.empty() && reader->GetOutput()->GetNumberOfPolys() == 0))
    throw SurfaceError(fmt::format("cannot read '{}' as {}: {}", path, ext == ".stl" ? "STL" : "OBJ", errors.first()));
  vtkNew<vtkTriangleFilter> triangles;
  triangles->SetInputData(reader->GetOutput());
  triangles->PassVertsOff();
  triangles->PassLinesOff();
  vtkNew<vtkCleanPolyData> clean;
  clean->SetInputConnection(triangles->GetOutputPort());
  clean->ConvertPolysToLinesOff();
  clean->ConvertLinesToPointsOff();
  clean->PointMergingOn();
  clean->Update();
  vtkSmartPointer<vtkPolyData> mesh = clean->GetOutput();
  if (mesh->GetNumberOfPolys() == 0)
    throw SurfaceError(fmt::format("'{}' holds no triangles; expected a closed surface", path));
  return mesh;
}

/// Checks that the triangles close a volume with outward normals: no open or non-manifold edge, every edge
/// walked once in each direction by its two triangles (consistent orientation), and a positive enclosed volume
/// (divergence theorem: the sum of x_a . (x_b x x_c) / 6 over the triangles). Returns that volume.
Real check_closed(vtkPolyData* mesh, const std::string& what) {
  vtkNew<vtkFeatureEdges> edges;
  edges->SetInputData(mesh);
  edges->BoundaryEdgesOn();
  edges->NonManifoldEdgesOn();
  edges->FeatureEdgesOff();
  edges->ManifoldEdgesOff();
  edges->Update();
  const vtkIdType open = edges->GetOutput()->GetNumberOfCells();
  if (open > 0)
    throw SurfaceError(fmt::format("{} is not closed: {} edges belong to one triangle or to more than two; expected a "
                                   "closed surface (a watertight mesh)",
                                   what, open));
  std::unordered_set<std::uint64_t> directed;
  const auto n_points = static_cast<std::uint64_t>(mesh->GetNumberOfPoints());
  double volume = 0;
  vtkCellArray* polys = mesh->GetPolys();
  vtkNew<vtkIdList> ids;
  for (polys->InitTraversal(); polys->GetNextCell(ids);) {
    if (ids->GetNumberOfIds() != 3) continue;
    double a[3], b[3], c[3];
    mesh->GetPoint(ids->GetId(0), a);
    mesh->GetPoint(ids->GetId(1), b);
    mesh->GetPoint(ids->GetId(2), c);
    volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
    for (int k = 0; k < 3; ++k) {
      const auto from = static_cast<std::uint64_t>(ids->GetId(k)), to = static_cast<std::uint64_t>(ids->GetId((k + 1) % 3));
      if (!directed.insert(from * n_points + to).second)
        throw SurfaceError(fmt::format("{} is not consistently oriented: two triangles walk the edge between points {} and "
                                       "{} in the same direction; expected every triangle's normal to point outward",
                                       what, from, to));
    }
  }
  if (!(volume > 0))
    throw SurfaceError(fmt::format("{} encloses a volume of {:.4g} m^3: {}", what, volume,
                                   volume < 0 ? "its normals point inward; expected outward normals (reverse every "
                                                "triangle's point order)"
                                              : "expected a surface that encloses a volume"));
  return volume;
}

/// The double nearest to the shortest decimal that reads as `f`.
double shortest_decimal(const float f) {
  char text[64];
  const auto end = std::to_chars(text, text + sizeof text - 1, f).ptr;
  *end = '\0';
  return std::strtod(text, nullptr);
}

/// The points of a polygon file: "x y" or "x, y" per line, '#' to the end of a line a comment.
std::vector<Vec> read_polygon_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SurfaceError(fmt::format("cannot open '{}'", path));
  std::vector<Vec> points;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    line = line.substr(0, line.find('#'));
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    double x = 0, y = 0;
    std::string rest;
    if (!(s >> x)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      throw SurfaceError(fmt::format("{}:{}: '{}': expected two numbers x y per line", path, number, line));
    }
    if (!(s >> y) || (s >> rest) || !std::isfinite(x) || !std::isfinite(y))
      throw SurfaceError(fmt::format("{}:{}: '{}': expected two finite numbers x y per line", path, number, line));
    Vec p = Vec::Zero();
    p[0] = x;
    p[1] = y;
    points.push_back(p);
  }
  return points;
}

}  // namespace

std::shared_ptr<const ClosedSurface> ClosedSurface::from_file(const std::string& path, const SurfaceTransform& transform) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw SurfaceError(fmt::format("cannot read '{}': {}", path, fs::exists(path, ec) ? "not a regular file" : "no such file"));
  if constexpr (dim == 2) {
    auto surface = from_polygon(read_polygon_file(path), transform);
    const_cast<ClosedSurface&>(*surface).source_ = path;
    return surface;
  } else {
    std::shared_ptr<ClosedSurface> s(new ClosedSurface());
    vtkSmartPointer<vtkPolyData> mesh = read_mesh(path);
    // VTK reads STL and OBJ coordinates as 32-bit floats (binary STL holds nothing else). Each is taken as the
    // shortest decimal that reads as the same float, so that a file written from decimal coordinates gives them
    // back (0.1f as 0.1, not 0.100000001) and a surface on the lattice stays on it; then transformed, in double.
    vtkPoints* read = mesh->GetPoints();
    vtkNew<vtkPoints> points;
    points->SetDataTypeToDouble();
    points->SetNumberOfPoints(read->GetNumberOfPoints());
    for (vtkIdType k = 0; k < read->GetNumberOfPoints(); ++k) {
      double x[3];
      read->GetPoint(k, x);
      Vec v;
      for (int a = 0; a < dim; ++a) v[a] = shortest_decimal(static_cast<float>(x[a]));
      v = transform.apply(v);
      for (int a = 0; a < dim; ++a) x[a] = v[a];
      if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
        throw SurfaceError(fmt::format("'{}' has a point that is not finite", path));
      points->SetPoint(k, x);
    }
    mesh->SetPoints(points);
    s->volume_ = check_closed(mesh, fmt::format("the surface in '{}'", path));
    double b[6];
    mesh->GetBounds(b);
    for (int a = 0; a < dim; ++a) s->bounds_.lo[a] = b[2 * a], s->bounds_.hi[a] = b[2 * a + 1];
    s->n_facets_ = static_cast<std::size_t>(mesh->GetNumberOfPolys());
    s->source_ = path;
    s->impl_->mesh = mesh;
    s->impl_->distance = vtkSmartPointer<vtkImplicitPolyDataDistance>::New();
    s->impl_->distance->SetInput(mesh);
    return s;
  }
}

std::shared_ptr<const ClosedSurface> ClosedSurface::from_polygon(std::vector<Vec> points, const SurfaceTransform& transform) {
  if constexpr (dim == 3) {
    throw SurfaceError("a polygon is a 2D shape; in 3D give a surface (an STL or OBJ file)");
  } else {
    if (points.size() >= 2 && points.front() == points.back()) points.pop_back();
    if (points.size() < 3)
      throw SurfaceError(fmt::format("a polygon of {} points; expected at least 3 points", points.size()));
    for (auto& p : points) p = transform.apply(p);
    const std::size_t n = points.size();
    for (std::size_t k = 0; k < n; ++k) {
      if (!points[k].allFinite()) throw SurfaceError(fmt::format("the polygon's point {} is not finite", k + 1));
      if (points[k] == points[(k + 1) % n])
        throw SurfaceError(fmt::format("the polygon's points {} and {} are the same; expected distinct consecutive points",
                                       k + 1, (k + 1) % n + 1));
    }
    std::shared_ptr<ClosedSurface> s(new ClosedSurface());
    auto& poly = s->impl_->polygon;
    for (const auto& p : points) poly.insert(poly.end(), {p[0], p[1], 0.0});
    // A simple polygon: no two edges that are not neighbours meet.
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 2; j < n; ++j) {
        if (i == 0 && j == n - 1) continue;  // the closing edge and the first are neighbours
        double u = 0, v = 0;
        if (vtkLine::Intersection(&poly[3 * i], &poly[3 * ((i + 1) % n)], &poly[3 * j], &poly[3 * ((j + 1) % n)], u, v) ==
            vtkLine::Intersect)
          throw SurfaceError(fmt::format("the polygon crosses itself: its edges {}-{} and {}-{} meet; expected a simple "
                                         "polygon",
                                         i + 1, (i + 1) % n + 1, j + 1, (j + 1) % n + 1));
      }
    double area = 0;  // the shoelace formula
    for (std::size_t k = 0; k < n; ++k) {
      const Vec& a = points[k];
      const Vec& b = points[(k + 1) % n];
      area += 0.5 * (a[0] * b[1] - b[0] * a[1]);
    }
    if (!(std::abs(area) > 0)) throw SurfaceError("the polygon encloses no area; expected a polygon with an inside");
    s->volume_ = std::abs(area);
    s->bounds_.lo = s->bounds_.hi = points[0];
    for (const auto& p : points) s->bounds_.lo = s->bounds_.lo.cwiseMin(p), s->bounds_.hi = s->bounds_.hi.cwiseMax(p);
    double* b = s->impl_->polygon_bounds;
    b[0] = s->bounds_.lo[0], b[1] = s->bounds_.hi[0], b[2] = s->bounds_.lo[1], b[3] = s->bounds_.hi[1];
    s->n_facets_ = n;
    s->source_ = fmt::format("a polygon of {} points", n);
    return s;
  }
}

Real ClosedSurface::signed_distance(const Vec& x, Vec& nearest) const {
  double p[3] = {0, 0, 0}, q[3] = {0, 0, 0};
  for (int a = 0; a < dim; ++a) p[a] = x[a];
  Real d = 0;
  if constexpr (dim == 3) {
    d = impl_->distance->EvaluateFunctionAndGetClosestPoint(p, q);
  } else {
    auto& poly = impl_->polygon;
    const std::size_t n = poly.size() / 3;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < n; ++k) {
      double t = 0, c[3];
      const double d2 = vtkLine::DistanceToLine(p, &poly[3 * k], &poly[3 * ((k + 1) % n)], t, c);
      if (d2 < best) best = d2, q[0] = c[0], q[1] = c[1];
    }
    double normal[3] = {0, 0, 1};
    const bool inside = best > 0 && vtkPolygon::PointInPolygon(p, static_cast<int>(n), const_cast<double*>(poly.data()),
                                                                impl_->polygon_bounds, normal) == 1;
    d = inside ? -std::sqrt(best) : std::sqrt(best);
  }
  for (int a = 0; a < dim; ++a) nearest[a] = q[a];
  return d;
}

SignedDistance ClosedSurface::distance_function(const std::shared_ptr<const ClosedSurface>& surface) {
  return [surface](const Vec& x, Vec& nearest) { return surface->signed_distance(x, nearest); };
}

}  // namespace mpsfsi
