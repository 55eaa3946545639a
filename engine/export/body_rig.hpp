#pragma once
// The fitted body model's skeleton and skinning weights carried over to another surface (M_bald):
// the skeleton is the body model posed as the fit left it (joints in the export frame, bind pose =
// the surface as exported), and each surface vertex takes the weights of the closest point of the
// fitted body (the three corners' weights blended by barycentric coordinates, the four largest kept
// and renormalised). The fitted body and M_bald describe the same skin, so the transferred
// weights bend M_bald where the body model bends.
#include "engine/body/body_fit.hpp"
#include "engine/body/body_model.hpp"
#include "engine/export/export_frame.hpp"
#include "engine/io/skeleton.hpp"

namespace nf::exporter {

// The fitted body in world units (posed from the fit's variables; regions and normals).
geometry::Mesh fitted_body_world(const body::BodyModel& model, const body::BodyFit& fit);

// `surface_world`: the surface to rig, in world units. Joint positions come out in the export frame.
io::Skeleton transfer_rig(const body::BodyModel& model, const body::BodyFit& fit, const geometry::Mesh& surface_world,
                          const ExportFrame& frame);

}  // namespace nf::exporter
