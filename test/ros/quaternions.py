"""Hamilton quaternions as (w, x, y, z) tuples, shared by the rostest checks: product, conjugate,
rotation of a vector, and the yaw between two attitudes (yawBetween in
include/vi_ekf_slam/core/so3.h)."""
import math


def qmul(a, b):
    """Hamilton product a * b."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def qconj(q):
    return (q[0], -q[1], -q[2], -q[3])


def rotate(q, v):
    """q v q*: the vector v turned by q."""
    return qmul(qmul(q, (0.0,) + tuple(v)), qconj(q))[1:]


def from_msg(q):
    """(w, x, y, z) of a geometry_msgs/Quaternion."""
    return (q.w, q.x, q.y, q.z)


def yaw_between(q_from, q_to):
    """The z rotation nearest to R_to R_from^T: defined whatever the body's axes (the heading of
    one body axis is not when it is near vertical, as EuRoC's IMU x axis is)."""
    d = qmul(q_to, qconj(q_from))
    x, y = rotate(d, (1.0, 0.0, 0.0)), rotate(d, (0.0, 1.0, 0.0))
    return math.atan2(x[1] - y[0], x[0] + y[1])
