"""An interactive 3-D view of a rig: one self-contained HTML page (plotly.js inlined, works offline).

:func:`pose_view` (a path to one pose, the page of ``csjm view``), :func:`poses_view`,
:func:`log_view`, :func:`designs_view`, :func:`diagnosis_view`; :func:`view_page` assembles any frames of
:class:`RigState` (:func:`rig_state`: planned tensions, K, or which cables cannot hold a load).
"""

from .diagnosis import diagnosis_view
from .page import ViewPage, view_page
from .plotly_js import PlotlyMissing
from .state import RigState, rig_state
from .views import designs_view, log_view, pose_view, poses_view, show
from .workspace import tilt_boundary_deg, workspace_traces

__all__ = ["PlotlyMissing", "RigState", "ViewPage", "designs_view", "diagnosis_view", "log_view", "pose_view",
           "poses_view", "rig_state", "show", "tilt_boundary_deg", "view_page", "workspace_traces"]
