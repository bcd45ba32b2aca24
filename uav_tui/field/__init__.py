"""Setting a drone up in the field: the boot service (:mod:`~uav_tui.field.service`, its unit file
:mod:`~uav_tui.field.unit`) and the setup check (:mod:`~uav_tui.field.doctor`, checks split by subject)."""
