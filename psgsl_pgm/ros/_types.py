"""The ROS 2 message types a GSL robot publishes, registered in a rosbags type store (no ROS install needed).

rosbags brings the standard ROS 2 (Humble) types — ``tf2_msgs/msg/TFMessage``, ``geometry_msgs``, ``nav_msgs``,
``std_msgs``. Two packages it lacks are registered here from their message definitions:

* ``olfaction_msgs/msg/GasSensor`` and ``olfaction_msgs/msg/Anemometer``: the message types of MAPIRlab's GSL
  stack (GADEN's simulated sensors, GasSourceLocalization), package ``MAPIRlab/olfaction_msgs``, files
  ``msg/GasSensor.msg`` and ``msg/Anemometer.msg``, licensed GPLv3 (psgsl-pgm is GPL-3.0-or-later). The field
  definitions below are those files' fields and constants (comments left out).
* ``vision_msgs/msg/Detection3DArray`` and the types it is built from (``ros-perception/vision_msgs`` 4.x,
  the ROS 2 Humble release; Apache-2.0).

A bag's own message definitions (MCAP storage carries them) are registered too when a type is neither here nor
in rosbags (:func:`typestore`).
"""

from __future__ import annotations

__all__ = ["ANEMOMETER", "DETECTIONS", "GAS_SENSOR", "MISSING_EXTRA", "UNITS_PPM", "UNIT_NAMES", "require", "typestore"]

#: The error message when the ``ros`` extra is missing.
MISSING_EXTRA = ('reading and writing ROS 2 bags and MCAP needs rosbags, mcap and foxglove-sdk (the "ros" extra): '
                 'pip install "psgsl-pgm[ros]"')

GAS_SENSOR = "olfaction_msgs/msg/GasSensor"
ANEMOMETER = "olfaction_msgs/msg/Anemometer"
DETECTIONS = "vision_msgs/msg/Detection3DArray"

#: ``GasSensor.raw_units`` value for ppm.
UNITS_PPM = 3

#: ``GasSensor.raw_units`` value -> unit name (the message definition's constants).
UNIT_NAMES = {0: "unknown", 1: "volt", 2: "ampere", 3: "ppm", 4: "ppb", 5: "ohm", 6: "ppm·m", 100: "°C",
              101: "% relative humidity", 255: "not valid"}

_GAS_SENSOR_MSG = """\
uint8 TECH_UNKNOWN=0
uint8 TECH_MOX=1
uint8 TECH_AEC=2
uint8 TECH_EQ=50
uint8 TECH_PID=51
uint8 TECH_SAW=52
uint8 TECH_TDLAS=53
uint8 TECH_TEMP=100
uint8 TECH_HUMIDITY=101
uint8 TECH_NOT_VALID=255
uint8 MANU_UNKNOWN=0
uint8 MANU_FIGARO=1
uint8 MANU_ALPHASENSE=2
uint8 MANU_SGX=3
uint8 MANU_RAE=50
uint8 MANU_HANWEI=51
uint8 MANU_NOT_VALID=255
uint8 MPN_UNKNOWN=0
uint8 MPN_TGS2620=50
uint8 MPN_TGS2600=51
uint8 MPN_TGS2611=52
uint8 MPN_TGS2610=53
uint8 MPN_TGS2612=54
uint8 MPN_MINIRAELITE=70
uint8 MPN_NOT_VALID=255
uint8 UNITS_UNKNOWN=0
uint8 UNITS_VOLT=1
uint8 UNITS_AMP=2
uint8 UNITS_PPM=3
uint8 UNITS_PPB=4
uint8 UNITS_OHM=5
uint8 UNITS_PPMXM=6
uint8 UNITS_CENTIGRADE=100
uint8 UNITS_RELATIVEHUMIDITY=101
uint8 UNITS_NOT_VALID=255
std_msgs/Header header
uint8 technology
uint8 manufacturer
uint8 mpn
float64 raw
uint8 raw_units
float64 raw_air
float64 calib_a
float64 calib_b
"""

_ANEMOMETER_MSG = """\
std_msgs/Header header
string sensor_label
float32 wind_speed
float32 wind_direction
"""

_VISION_MSGS = {
    "vision_msgs/msg/ObjectHypothesis": "string class_id\nfloat64 score\n",
    "vision_msgs/msg/ObjectHypothesisWithPose": "vision_msgs/ObjectHypothesis hypothesis\n"
                                                "geometry_msgs/PoseWithCovariance pose\n",
    "vision_msgs/msg/BoundingBox3D": "geometry_msgs/Pose center\ngeometry_msgs/Vector3 size\n",
    "vision_msgs/msg/Detection3D": "std_msgs/Header header\nvision_msgs/ObjectHypothesisWithPose[] results\n"
                                   "vision_msgs/BoundingBox3D bbox\nstring id\n",
    DETECTIONS: "std_msgs/Header header\nvision_msgs/Detection3D[] detections\n",
}


def require():
    """Import rosbags; ImportError naming the ``ros`` extra when it is missing.

    Raises
    ------
    ImportError
        rosbags is not installed; the message names the ``ros`` extra to install.

    Examples
    --------
    >>> from psgsl_pgm.ros import require
    >>> require()                                               # silent when the ros extra is installed
    """
    try:
        import rosbags.rosbag2
        import rosbags.typesys  # noqa: F401
    except ModuleNotFoundError as err:
        if (err.name or "").split(".")[0] != "rosbags":
            raise
        raise ImportError(MISSING_EXTRA) from err


def typestore(connections=()):
    """A rosbags type store: ROS 2 Humble, the olfaction and vision types above, and the message definitions
    that ``connections`` (rosbags connections of a bag) carry for types it does not know yet."""
    require()
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    types.update(get_types_from_msg(_GAS_SENSOR_MSG, GAS_SENSOR))
    types.update(get_types_from_msg(_ANEMOMETER_MSG, ANEMOMETER))
    for name, text in _VISION_MSGS.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    extra = {}
    for conn in connections:
        msgdef = getattr(conn, "msgdef", None)
        text = getattr(msgdef, "data", None) if msgdef is not None else None
        if conn.msgtype in store.types or not text:
            continue
        extra.update(_parse_definitions(text, conn.msgtype))
    if extra:
        store.register({k: v for k, v in extra.items() if k not in store.types})
    return store


def _parse_definitions(text: str, msgtype: str) -> dict:
    """The types of a bag's message definition: ``msgtype``'s own fields, then ``MSG: pkg/Type`` blocks after
    lines of ``=`` (the ROS 2 MCAP layout). A definition rosbags cannot parse gives nothing (the type then stays
    unknown and the reader names it)."""
    from rosbags.typesys import TypesysError, get_types_from_msg

    blocks, name, lines = [], msgtype, []
    for line in text.splitlines():
        if line.startswith("=") and set(line.strip()) == {"="}:
            blocks.append((name, "\n".join(lines)))
            name, lines = None, []
        elif name is None and line.startswith("MSG: "):
            pkg, _, typ = line[5:].strip().partition("/")
            name = f"{pkg}/msg/{typ}" if "/msg/" not in line else line[5:].strip()
        else:
            lines.append(line)
    blocks.append((name, "\n".join(lines)))
    out = {}
    for name, body in blocks:
        if name is None:
            continue
        try:
            out.update(get_types_from_msg(body, name))
        except TypesysError:
            continue
    return out
