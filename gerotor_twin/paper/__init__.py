"""Section 4 of the paper: tables 3–5, figures 12–16, calibration of the clearances.

=================  =====================================================================
module             responsibility
=================  =====================================================================
reference          the paper's published values (tables 3–5) and the slope definition
setting            the pump as calibrated: eq. (23) and ray kidney edges (``paper_setting``)
efficiency         model efficiency at the table points (any outer-gear model)
calibration        least-squares fit of δ and the lateral clearance to the fixed rows
section4           the sec. 4 operating point (restriction line) run for the four models
figures            counterparts of figs. 12–16 (matplotlib)
cli_commands       ``gerotor-twin paper efficiency|figures|calibrate``
=================  =====================================================================
"""
