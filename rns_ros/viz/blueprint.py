"""The viewer layouts: the 3D scene large on the left, the time series grouped on the right.

:func:`default_blueprint` for the free-floating robot, :func:`contact_blueprint` for a Part II
fixed-base arm in contact."""

from __future__ import annotations

import rerun.blueprint as rrb

from rns_ros.viz import paths


def default_blueprint() -> rrb.Blueprint:
    """3D view (everything but plots and logs) | stacked plots, extra plots in tabs.

    The 3D view's origin is the root so that ``/tf_static`` (the URDF's fixed joint origins,
    logged outside ``world``) is in the view together with the scene.
    """
    scene = rrb.Spatial3DView(
        name="Satellite and arm",
        origin="/",
        contents=[
            "+ /**",
            f"- /{paths.PLOTS}/**",
            f"- /{paths.CONTROLLER_LOG}",
            f"- /{paths.PTP_LOG}",
        ],
    )
    plots = rrb.Vertical(
        rrb.TimeSeriesView(name="Base attitude deviation [deg]", origin=paths.BASE_ATTITUDE),
        rrb.TimeSeriesView(
            name="Predicted coupling momentum M~θ̇ [kg m²/s]", origin=paths.COUPLING_MOMENTUM
        ),
        rrb.TimeSeriesView(
            name="Camera angular velocity, world axes [rad/s]", origin=paths.ANGULAR_VELOCITY
        ),
        rrb.TimeSeriesView(name="Joint velocities [rad/s]", origin=paths.JOINT_VELOCITY),
        rrb.TimeSeriesView(
            name="Singularity measures [-]",
            origin=paths.SINGULARITY,
            # det_coupling is ~1e13 (kg m²)⁶: it would flatten the others, so it has its own tab.
            contents=["+ $origin/**", f"- /{paths.DET_COUPLING}"],
        ),
        rrb.Tabs(
            rrb.TimeSeriesView(name="Controller", origin=paths.CONTROLLER),
            rrb.TextLogView(name="Controller log", origin=paths.CONTROLLER_LOG),
            rrb.TimeSeriesView(name="Kinetic energy [J]", origin=paths.ENERGY),
            rrb.TimeSeriesView(name="Reaction wheels", origin=paths.WHEELS),
            rrb.TimeSeriesView(name="Point-to-point (rns_ptp)", origin=paths.PTP),
            rrb.TextLogView(name="rns_ptp log", origin=paths.PTP_LOG),
            rrb.TimeSeriesView(name="System momentum", origin=paths.MOMENTUM),
            rrb.TimeSeriesView(name="det(M~ M~ᵀ) [(kg m²)⁶]", origin=paths.DET_COUPLING),
        ),
    )
    return rrb.Blueprint(
        rrb.Horizontal(scene, plots, column_shares=[3, 2]),
        rrb.TimePanel(timeline=paths.TIMELINE),
        collapse_panels=False,
    )


def contact_blueprint() -> rrb.Blueprint:
    """Part II layout (fixed-base arm in contact, docs/part2_ros.md): 3D view of the arm, the
    environment and the force arrows | force, position error and contact plots stacked, joint
    velocities and the orientation error in tabs."""
    scene = rrb.Spatial3DView(
        name="Arm and environment",
        origin="/",
        contents=["+ /**", f"- /{paths.PLOTS}/**", f"- /{paths.CONTROLLER_LOG}"],
    )
    plots = rrb.Vertical(
        rrb.TimeSeriesView(name="Normal force: desired, measured, error [N]", origin=paths.FORCE),
        rrb.TimeSeriesView(
            name="Position error p_des - p, world axes [m]",
            origin=paths.POSITION_ERROR,
            contents=["+ $origin/**", f"- /{paths.POSITION_ERROR_ORIENTATION}"],
        ),
        rrb.TimeSeriesView(
            name="Contact: normal force λ [N]",
            origin=paths.CONTACT_PLOTS,
            contents=[f"+ /{paths.CONTACT_NORMAL_FORCE}"],
        ),
        rrb.Tabs(
            rrb.TimeSeriesView(name="Joint velocities [rad/s]", origin=paths.JOINT_VELOCITY),
            rrb.TimeSeriesView(
                name="Gap φ [m] (> 0 penetration)",
                origin=paths.CONTACT_PLOTS,
                contents=[f"+ /{paths.CONTACT_GAP}"],
            ),
            rrb.TimeSeriesView(
                name="Orientation error [rad]", origin=paths.POSITION_ERROR_ORIENTATION
            ),
        ),
    )
    return rrb.Blueprint(
        rrb.Horizontal(scene, plots, column_shares=[3, 2]),
        rrb.TimePanel(timeline=paths.TIMELINE),
        collapse_panels=False,
    )
