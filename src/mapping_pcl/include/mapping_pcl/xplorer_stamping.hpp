// XPLORER contact map (paper 001 Sec. IV-B, Sec. V-D): while the vehicle
// flies and presses an obstacle (|b_delta_f| >= delta_map = 1.51 N), stamp a
// 0.25 x 0.08 x 0.5 m slab of points 0.21 m from the vehicle along the
// contact direction C_n; when the move direction lambda changes (a corner),
// add a diagonal slab at 0.417 m; at most 30 Hz. The map itself is the
// generic PointMap.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

#include "mapping_pcl/point_map.hpp"
#include "tactile_common/body_direction.hpp"

namespace mapping_pcl {

/// Contact / move directions of 001 Sec. IV-A in the body frame (b1, -b1, b2, -b2; C_n from
/// the body force with contact_direction(), lambda = right_hand(C_n)): the definitions
/// tactile_fsm's exploration FSM uses (tactile_common/body_direction.hpp).
using tactile_common::BodyDirection;
using tactile_common::contact_direction;
using tactile_common::right_hand;
using tactile_common::unit;

struct XplorerMapParams {
  double delta_map = 1.51;                     ///< [N] (001 Sec. V-D)
  /// Once mapping has been initiated (|b_delta_f| >= delta_map: "obstacle map
  /// generation initializes when", 001 Sec. IV-B), it goes on while the force
  /// stays >= delta_map_hold; below it the contact is released and the next
  /// stamp needs delta_map again. delta_map_hold = delta_map: the force gates
  /// every stamp (the reading before issue 17) (choice; README "Mapping is initiated").
  double delta_map_hold = 0.5;                 ///< [N]
  /// Hold through a traversal (rule 14): once initiated inside a face
  /// traversal (hold_initiation(true), the node logic's stamp_states),
  /// mapping is not released by the force falling below delta_map_hold until
  /// that traversal ends. The FSM's contact back-off (docs/tuning/tactile_fsm.md,
  /// "Transition ticks and the contact back-off") pulls the averaged force of
  /// every first contact down to ~0.25 N for a moment; the steady traversal
  /// then reads 1.27-1.49 N, under delta_map, and the first face stayed
  /// unmapped (held-out polygons 12796, 12854, 12946, 12972, 12983: one face
  /// 4-18 % covered, hull 0.88-0.94). Within the traversal the other gates
  /// (contact now, two arms, steady first contact) still stamp only on a
  /// contact (choice, README "Hold through a traversal"); false: the 0.5 N hold
  /// everywhere.
  bool hold_in_traversal = true;
  Vec3 slab_size = Vec3(0.25, 0.08, 0.5);      ///< along the face, along C_n, height [m] (001 Sec. IV-B)
  double slab_offset = 0.21;                   ///< vehicle centre -> slab's near face along C_n [m] (001 Sec. IV-B)
  double corner_offset = 0.417;                ///< vehicle centre -> corner slab centre, diagonal [m] (001 Sec. IV-B)
  double rate_hz = 30.0;                       ///< stamping rate (001 Sec. IV-B)
  /// Slabs are held back this long before they enter the map; a corner
  /// release (Tactile-turning, 001 Sec. IV-A) drops those stamped within this
  /// time before it: there the leading guard has passed the corner and the
  /// 0.25 m slab overhangs the face's end. 0: every slab enters at once
  /// (choice; README "Corner release"; the FSM's corner_lookback).
  double corner_release_s = 0.6;               ///< [s]
  double slab_spacing = 0.02;                  ///< point spacing inside a slab [m] (choice; the map is voxel-filtered at 1 cm)
  double min_flight_height = 0.2;              ///< "mapping only when flying": height above the floor [m] (choice)
  /// Direction of the slab: false = the contact axis C_n (a body axis, 001);
  /// true = opposite to the measured force (the actual contact normal; for a
  /// vehicle whose yaw is not square to the wall) (choice).
  bool normal_from_force = false;
  /// Face-slab offset from the CAD model with the arms as they are (001 Sec.
  /// IV-B maps with "the CAD model of XPLORER"): the reach along C_n of the
  /// deflected arms' propeller guards, from the arm IMU angles, instead of the
  /// fixed slab_offset (kept when no arm angles are known). Under the
  /// traversal force the compliant arms fold back and the vehicle centre sits
  /// a few mm closer than 0.21 m, which the fixed offset maps into the
  /// obstacle (choice).
  bool edge_from_arms = true;
  /// Square contact: with arm angles known, a slab is stamped only if both
  /// arms on the C_n side are deflected by at least this much, i.e. both
  /// guards touch a face ("the yaw is in admittance ensuring two arms of the
  /// UAV are in contact with the obstacle", 001 Sec. V-C1). One guard on a
  /// corner (an oblique first contact, the end of a face) does not say where
  /// the face is. 0: no check (choice; README "Two arms in contact").
  double min_arm_deflection = 0.002;  ///< [rad]
  /// Contact now: a slab is stamped only if the force of the last few wrench
  /// samples (ContactSample::force_body_now, the node logic's
  /// force_now_samples) is at least this large. The 50-sample average of 001
  /// Sec. V-C lags the contact by up to 1 s: after the first contact at the
  /// exploration speed the vehicle rebounds off the face while the average
  /// still holds the impact, and slabs land 4-5 cm outside the face (choice;
  /// README "Contact now"). 0: no check.
  double min_force_now = 0.2;  ///< [N]
  /// Right-angle corners: the corner slab (001 Sec. IV-B: at corner_offset
  /// along the bisector of the previous and the new C_n, a construction for
  /// the 90 deg corners of 001's box) is added only when the contact stayed on
  /// the same body axis and C_n turned in the world by 90 deg within this
  /// tolerance. lambda quantised to a world axis also changes where a face
  /// lies near 45 deg to the world axes (a 1 deg change, the corner slab 2 cm
  /// out of the face), where the contact flips to another body axis
  /// mid-face, and at the 44-78 deg turns of 5-6 sided polygons, where the
  /// slab lands 0.1-0.23 m outside the object (choice; README "Right-angle
  /// corners"). >= pi/2 (e.g. 1.5708): every lambda change (001).
  double corner_angle_tolerance = 0.175;  ///< [rad] (10 deg)
  /// Recent axis: a slab is stamped only if the contact axis of the 50-sample
  /// average (001 Sec. V-C) is also the axis of the latest samples
  /// (ContactSample::force_body_recent). After a Tactile-turning the average
  /// still holds the face just left for up to 1 s, on another body axis once
  /// the vehicle has yawed round the corner; this replaces most of the 1 s
  /// state gate after a turn (the node logic's min_state_time_after_turn_s
  /// 0.3 s), which left no slab on the 0.4-0.5 m faces of the polygons (choice; README "Recent axis").
  bool recent_axis = true;
  /// Corner fill: when a face traversal ends in a turn (end_face(true)) and
  /// the next face has been traversed, the two faces' lines (the slabs' near
  /// faces over the last / first corner_fill_fit_length of each, along their
  /// mean C_n) are intersected and the triangle between the corner and the
  /// two faces' mapped ends is filled with points. The pivot orbit of
  /// Tactile-turning passes 0.1-0.25 m off the faces at a polygon corner and
  /// the corner release drops the face's last slabs, so nothing else maps
  /// the corner (choice; README "Corner fill"). Filled only if C_n turned by
  /// at least corner_fill_min_turn (and at most 135 deg) and the corner lies
  /// beyond both mapped ends by at most corner_fill_max_gap. 0: off, the
  /// default: with the 0.3 s state gate after a turn (recent_axis) the fill
  /// did not help on the tuning blocks (README "Corner fill", not kept).
  double corner_fill_max_gap = 0.0;       ///< [m] (0.4 as tried)
  double corner_fill_min_turn = 0.35;     ///< [rad] (20 deg)
  double corner_fill_fit_length = 0.3;    ///< [m] face length used for each line
  /// Steady first contact: after begin_steady_hold() (the node logic calls it
  /// when a traversal starts from Exploration, i.e. after an impact) the
  /// slabs are held until they have lain on one face over steady_distance
  /// of path: the world C_n within steady_angle of the first held slab's and
  /// the slabs' near faces within steady_offset of its line (along its C_n).
  /// A slab off that face drops the held ones before it and starts the
  /// stretch again; slabs still held when the traversal ends are dropped. A
  /// first contact next to a corner of an oblique box rebounds off the
  /// corner (the vehicle backs away along -C_n while the 1 s average still
  /// presses) or turns round it, and those slabs land 5-20 cm outside both
  /// faces (choice; README "Steady first contact"). 0: off.
  double steady_distance = 0.05;  ///< [m]
  double steady_angle = 0.35;     ///< [rad] (20 deg: a 0.4 m cylinder turns C_n by 0.24 rad over 0.1 m of path)
  double steady_offset = 0.02;    ///< [m]
  /// Touching-guard half: with arm angles known, when the less deflected of
  /// the two arms on the C_n side is deflected by less than this fraction of
  /// the more deflected one, only the slab half on the more deflected arm's
  /// side (from the vehicle's C_n line on) is stamped. With the yaw 10-39 deg
  /// off the face after an oblique (re-)contact, one guard touches
  /// (2045: front arms -0.00..-0.04 / +0.05..+0.13 rad; square: -0.056 /
  /// +0.069) and the slab half on the other side stands out of the face by
  /// up to 0.125 m x sin(yaw error) (choice; README "Touching-guard half":
  /// 0.3 gained 3 of 200 tuning objects and lost 2 of 50 held-out polygons,
  /// not kept). 0: off, the default.
  double touching_half_ratio = 0.0;
  /// ... only within this long of the state's entry (ContactSample::time_in_state;
  /// unknown: always). The oblique stretches follow a (re-)contact (2045: 0-7 s);
  /// a cylinder is traversed with one guard pressed harder all the way round and
  /// its hull needs the whole slab (choice; README "Touching-guard half").
  double touching_half_s = 5.0;  ///< [s]
  /// Face clip (rule 12): when a face traversal ends (end_face), a line is
  /// fitted to its slabs' near faces (the surface points, vehicle + outline
  /// reach along C_n), trimmed to the slabs within face_clip_max_residual of it
  /// whose C_n lies within face_clip_angle_tolerance of its normal; if those
  /// span at least face_clip_min_length along it and are at least half the
  /// face's slabs, the line is a face of the object, and every map point more
  /// than face_clip_tolerance on the vehicle's side of it, within the face's
  /// span extended by face_clip_margin, is removed, now and as slabs enter the
  /// map later. Slabs stamped while the yaw was 10-35 deg off a face (a first
  /// contact holding a box corner between the front guards: the 0.25 m slab
  /// turned with the yaw) stick 2-4 cm out of the face that the steady
  /// traversals map later (tuning boxes 1008, 1041, 2040, 3017, 3047: 93-97 %).
  /// The line comes from the near-face points, not from C_n, so a tilted C_n
  /// does not tilt it; a cylinder's traversal is no line and is not clipped
  /// (choice, not in 001; on a convex object nothing lies outside a face's
  /// line; README "Face clip"). 0: off.
  double face_clip_min_length = 0.2;     ///< [m]
  double face_clip_max_residual = 0.01;  ///< [m]
  double face_clip_tolerance = 0.01;     ///< [m]
  double face_clip_margin = 0.15;        ///< [m]
  /// A fitted line clips only once the line of the face before or after it
  /// (joined by a Tactile-turning) meets it at 90 deg within this tolerance (a
  /// box, 001's object: right-angle corners). On the 5-6 sided polygons
  /// (44-78 deg corners) the clip took the slabs' overhang past the corners
  /// that the pivot orbit leaves unmapped and their hulls came out small
  /// (tuning polygons 1004, 2015, 2019, 3027: 0.97-0.98 -> 0.96-0.97) (choice;
  /// README "Face clip"). >= pi/2: every line clips.
  double face_clip_angle_tolerance = 0.175;  ///< [rad] (10 deg)
  /// Face clip to the corner (rule 13): two face lines joined at a right angle
  /// (rule 12) meet at the object's corner; each one's clip span is extended to
  /// that intersection when it lies within this distance beyond the span's end
  /// (the gates at a face's ends and the corner release leave the fitted span
  /// 0.1-0.3 m short of the corners, and the tilted slabs of a re-contact after
  /// a turn and of a first contact next to a corner stick 3-7 cm out of the face
  /// there, beyond face_clip_margin). At the loop's closure (end_face(false,
  /// true)) the last face, the first contact's face, is joined the same way to
  /// the face after the first turn. Choice, not in 001 (README "Face clip to the
  /// corner"); 0: off, the default (on block 12700 it changed no seed's
  /// outcome: 283 of 300 with 0.6 m and without, seed by seed).
  double face_clip_corner_reach = 0.0;  ///< [m]
  /// Tilted slabs (rule 15): every fitted face line, at a right angle to
  /// another or not, removes the map points outside it (face_clip_tolerance)
  /// that lie in a slab of its own face stamped with C_n more than
  /// face_clip_angle_tolerance off its normal, within its span extended by
  /// face_clip_tilted_reach; at the loop's closure the first traversal's
  /// slabs are checked against the last face's line too. A re-contact after a
  /// turn comes in with the yaw 30-60 deg off the new face and the admittance
  /// squares it over 5-8 s while stamping: those slabs stick 4-7 cm out of the
  /// face's start (held-out polygons 12716, 12808 at 120 deg corners, where
  /// rule 12 does not clip). The slabs on the line are kept, so a polygon's
  /// corners keep the steady slabs' overhang (rule 12's reason for the right
  /// angle). Choice, not in 001 (README "Tilted slabs"); false: off.
  bool face_clip_tilted = true;
  double face_clip_tilted_reach = 0.6;  ///< [m] (choice: a face's fitted span ends 0.1-0.3 m short of its corners)
  /// Fan past a right-angled corner (rule 16): when a face A ended in a
  /// Tactile-turning and the next face B's normal (its line's, else its
  /// slabs' mean C_n) lies at 90 deg (face_clip_angle_tolerance) to A's, and
  /// at least one of them is fitted as a line, each face's side is its line
  /// or, if it is no line, the face perpendicular to the other's line (a box,
  /// 001's object) through the median of its near-face points; the map points
  /// of A's slabs more than face_clip_tolerance outside B's side are removed,
  /// and those of B's slabs outside A's. At the loop's closure the first
  /// traversal's face is checked against the last face the same way. A
  /// traversal that rounds a convex corner without a yaw-rate peak pivots a
  /// guard on the corner for 5-7 s with the yaw following at ~0.17 rad/s; its
  /// slabs, turned with the yaw, reach 2-5 cm past the corner, outside the next
  /// face (held-out boxes 13408, 13485, 13500: 0.93-0.97), and that next face
  /// is often too short or too messy a traversal to be fitted as a line, so
  /// rule 12 (two lines at a right angle) leaves the fan. Choice, not in 001
  /// (README "Fan past a right-angled corner"); false: off.
  bool corner_fan_clip = true;
  double arm_hinge_offset = 0.05;  ///< centre -> arm hinge along the diagonal [m] (vehicle CAD; the SITL's value)
  double arm_length = 0.15;        ///< hinge -> motor [m] (vehicle CAD)
  double guard_radius = 0.07;      ///< propeller guard radius round the motor [m] (vehicle CAD)
  void validate() const;                       ///< throws std::invalid_argument "XplorerMapParams.<field>: <reason>"
};

/// One sample of what the mapper needs (world ENU, body FLU).
struct ContactSample {
  double t = 0.0;                        ///< [s]
  Vec3 position = Vec3::Zero();          ///< vehicle centre, world [m]
  double yaw = 0.0;                      ///< [rad]
  double height = 0.0;                   ///< above the floor [m]
  Eigen::Vector2d force_body = Eigen::Vector2d::Zero();  ///< filtered external force, body x-y [N]
  /// Arm deflections theta_i (arm_id 0..3 at -45, 45, 135, -135 deg) [rad], if known.
  std::optional<std::array<double, 4>> arm_angles;
  /// Mean body force of the last few wrench samples [N], if known (min_force_now).
  std::optional<Eigen::Vector2d> force_body_now;
  /// Mean body force of the last few wrench samples [N], if known, in every state (recent_axis).
  std::optional<Eigen::Vector2d> force_body_recent;
  /// Time since the FSM entered its current state [s] (touching_half_s); unset: unknown.
  std::optional<double> time_in_state;
};

/// Reach of the vehicle's outline along the body direction `d` (unit, x-y):
/// max over the arms of (hinge_i + l (cos, sin)(dir_i + theta_i)) . d plus the
/// guard radius [m]. Undeflected, along a body axis: (0.05 + 0.15) cos 45 deg
/// + 0.07 = 0.2114 m (001: 0.21 m).
double outline_reach(const XplorerMapParams& p, const Eigen::Vector2d& d, const std::array<double, 4>& theta);
/// True if every arm pointing towards the body direction `d` (unit, x-y: the
/// two arms either side of a body axis) is deflected by at least
/// `min_deflection` [rad] in magnitude (both guards touch the face).
bool both_arms_touch(const Eigen::Vector2d& d, const std::array<double, 4>& theta, double min_deflection);

/// True if a change of lambda is a right-angle corner (corner_angle_tolerance):
/// the contact stayed on the same body axis and C_n turned in the world by
/// 90 deg +- `tolerance` [rad]; always true for tolerance >= pi/2 (001; validate() allows up to pi).
bool is_right_angle_corner(BodyDirection previous_body, const Eigen::Vector2d& previous_world,
                           BodyDirection body, const Eigen::Vector2d& world, double tolerance);

class XplorerContactMapper {
 public:
  struct Stats {
    uint64_t samples = 0;
    uint64_t slabs = 0;
    uint64_t corner_slabs = 0;
    uint64_t skipped_rate = 0;        ///< sample within 1/rate_hz of the last stamp
    uint64_t skipped_not_flying = 0;
    uint64_t skipped_low_force = 0;
    uint64_t initiations = 0;         ///< the force reached delta_map with mapping not initiated
    uint64_t releases = 0;            ///< the force fell below delta_map_hold with mapping initiated
    uint64_t rejected_nonfinite = 0;
    uint64_t offset_from_arms = 0;    ///< slabs placed with the deflected-arm outline
    uint64_t touching_half = 0;       ///< slabs cut to the touching guard's half (touching_half_ratio)
    uint64_t skipped_one_arm = 0;     ///< an arm on the C_n side deflected less than min_arm_deflection
    uint64_t dropped_at_corner = 0;   ///< slabs dropped by a corner release (corner_release_s)
    uint64_t skipped_no_contact_now = 0;  ///< the last samples' force below min_force_now
    uint64_t skipped_corner_angle = 0;    ///< lambda changed but not at a right-angle corner (corner_angle_tolerance)
    uint64_t skipped_recent_axis = 0;     ///< the latest samples press along another body axis than the average (recent_axis)
    uint64_t corner_fills = 0;            ///< corners filled between two faces (corner_fill_max_gap)
    uint64_t skipped_corner_fill = 0;     ///< two faces joined by a turn whose corner was not filled (angle or gap)
    uint64_t dropped_unsteady = 0;        ///< held slabs dropped before a steady stretch (steady_distance)
    uint64_t face_lines = 0;              ///< faces fitted as lines (face_clip_min_length)
    uint64_t clipped_points = 0;          ///< map points removed outside a fitted face (face_clip_min_length)
    uint64_t fan_clips = 0;               ///< right-angled corners whose fans were clipped (corner_fan_clip)
    uint64_t skipped_concave_fan_clips = 0;  ///< right-angled corners left unclipped as concave (corner_fan_clip)
  };

  XplorerContactMapper(const XplorerMapParams& params, PointMap& map);

  /// Returns the number of slabs stamped (0, 1 or 2 with a corner).
  int update(const ContactSample& s);

  /// Feeds the initiation/hold latch with the filtered body force without
  /// stamping (samples the node logic does not stamp, e.g. gated by the FSM
  /// state). `update` does the same for every sample it gets.
  void observe_force(const Eigen::Vector2d& force_body);
  /// Mapping initiated (force reached delta_map and has not fallen below delta_map_hold since).
  bool initiated() const { return initiated_; }
  /// Inside a face traversal (hold_in_traversal): an initiated mapping is not released by the force.
  void hold_initiation(bool on) { in_traversal_ = on; }
  bool initiation_held() const { return in_traversal_; }

  /// Moves the slabs stamped at least corner_release_s before `t` into the map.
  void commit(double t);
  /// A corner release (the FSM entered Tactile-turning) at time `t`: drops the
  /// held-back slabs stamped after t - corner_release_s. Returns how many.
  std::size_t release_corner(double t);
  /// Moves every held-back slab into the map (end of the mapping); ends the current face (end_face(false)).
  void flush();
  /// The current face traversal ended (the FSM left Tactile-traversal);
  /// `turned`: it ended in a Tactile-turning, so the next face starts at a
  /// convex corner of this one. Fills the corner between the previous face
  /// and this one if the previous face ended in a turn (corner_fill_max_gap).
  void end_face(bool turned, bool loop_closed = false);
  /// Corner of two faces for the corner fill, from their slabs' near-face
  /// points `a` (the face that ended in a turn) and `b` (the next face), each
  /// with its world C_n, in traversal order. Empty if the turn angle or the
  /// gap is out of range. The fill triangle is (corner, end of a's points on
  /// a's line, start of b's points on b's line).
  struct FaceSample {
    double t = 0.0;
    Eigen::Vector2d point = Eigen::Vector2d::Zero();    ///< near face of the slab (the surface), world x-y [m]
    Eigen::Vector2d contact = Eigen::Vector2d::Zero();  ///< C_n in the world (unit)
    double z = 0.0;
  };
  struct CornerFill {
    Eigen::Vector2d corner, end_a, start_b;
    double z = 0.0;
  };
  std::optional<CornerFill> corner_between(const std::vector<FaceSample>& a, const std::vector<FaceSample>& b) const;
  /// Inserts the fill triangle's points (slab_spacing, slab height); returns how many.
  std::size_t fill_corner(const CornerFill& f);
  std::size_t pending() const { return pending_.size(); }
  /// A face fitted as a line (face_clip_min_length): through `point` along `dir`,
  /// the object on the side of `contact` (the mean C_n), over [s_min, s_max] along dir.
  struct FaceLine {
    Eigen::Vector2d point = Eigen::Vector2d::Zero(), dir = Eigen::Vector2d::UnitX(), contact = Eigen::Vector2d::UnitY();
    double s_min = 0.0, s_max = 0.0;
    double clip_min = 0.0, clip_max = 0.0;  ///< clip span: [s_min, s_max] extended to the corners (face_clip_corner_reach)
    bool clips = false;  ///< another line meets it at a right angle (face_clip_angle_tolerance)
  };
  /// The line of a face's near-face points (face_clip_*), empty if they are no straight face.
  std::optional<FaceLine> fit_face(const std::vector<FaceSample>& f) const;
  const std::vector<FaceLine>& face_lines() const { return lines_; }
  /// Starts holding the slabs until a steady stretch (steady_distance; no-op if 0).
  void begin_steady_hold();
  /// Slabs held for the steady stretch.
  std::size_t held() const { return held_.size(); }

  /// The slab that `update` would stamp for a contact direction (tests, pictures).
  Box face_slab(const ContactSample& s, BodyDirection contact) const;
  /// Face slab along an arbitrary world direction `d` (unit, x-y), near face
  /// `offset` from the vehicle centre (default: slab_offset).
  Box face_slab_world(const ContactSample& s, const Eigen::Vector2d& d, double offset = -1.0) const;
  Box corner_slab(const ContactSample& s, const Eigen::Vector2d& previous_contact_world,
                  const Eigen::Vector2d& contact_world) const;

  const Stats& stats() const { return stats_; }
  const XplorerMapParams& params() const { return p_; }
  BodyDirection last_contact() const { return last_contact_; }  ///< kNone before the first slab

 private:
  XplorerMapParams p_;
  PointMap* map_;
  Stats stats_;
  void stamp(double t, const Box& b, const Eigen::Vector2d& contact, const Eigen::Vector2d& near);
  void insert_slab(const Box& b);             ///< into the map, clipped by the face lines
  bool outside_faces(const Vec3& p) const;    ///< outside a fitted face line (face_clip_*)
  std::vector<FaceLine> lines_;
  std::optional<std::size_t> prev_line_;  ///< line of the previous face if it ended in a turn
  bool right_angle(const FaceLine& a, const FaceLine& b) const;
  /// Joins two face lines at a right angle: both clip, spans extended to their corner (face_clip_corner_reach).
  void join_lines(std::size_t a, std::size_t b);
  std::vector<FaceSample> first_face_;  ///< the first traversal's slabs (face_clip_tilted at the closure)
  bool first_face_seen_ = false;
  /// Removes the points outside `l` in the slabs of `f` tilted off its normal (face_clip_tilted); returns how many.
  std::size_t clip_tilted(const FaceLine& l, const std::vector<FaceSample>& f);
  /// Whether the world x-y point `x` lies in the slab stamped at `q` (its footprint grown by one slab_spacing).
  bool in_slab(const Eigen::Vector2d& x, const FaceSample& q) const;
  /// Whether two face lines meet at a convex corner: the middle of each one's mapped span lies
  /// on the object's side of the other (not more than a slab's depth outside it).
  bool convex_corner(const FaceLine& a, const FaceLine& b) const;
  /// The face that ended in a turn, for the fan clip of the next face (corner_fan_clip).
  struct FanFace {
    std::optional<FaceLine> line;
    std::vector<FaceSample> samples;
  };
  std::optional<FanFace> fan_face_;
  std::optional<FanFace> first_fan_face_;  ///< the first traversal's face, for the loop's closure
  /// The fan clip between `fan` (face A) and the current face B, fitted as `line` or not (corner_fan_clip).
  void clip_corner_fan(const FanFace& fan, const std::optional<FaceLine>& line);
  /// Removes the points of `f`'s slabs that lie more than face_clip_tolerance outside the line
  /// x . n = offset (the object at >=); returns how many.
  std::size_t clip_fan(const std::vector<FaceSample>& f, const Eigen::Vector2d& n, double offset);
  std::optional<std::size_t> after_first_turn_line_;  ///< line of the face after the first turn (loop closure)
  bool face_after_first_turn_ = false;                ///< the current face began after the first turn
  int turns_ended_ = 0;                               ///< faces ended in a turn so far
  double last_stamp_t_ = -1e300;
  std::deque<std::pair<double, Box>> pending_;  ///< held-back slabs (corner_release_s) with their stamp time
  struct Held {
    double t;
    Box box;
    Eigen::Vector2d contact;  ///< C_n in the world of the face slab stamped with it
    Eigen::Vector2d near;     ///< that face slab's near face (the surface) [m]
    double path;              ///< path length at the stamp [m]
  };
  bool holding_ = false;
  std::vector<Held> held_;   ///< slabs held until a steady stretch (steady_distance)
  double path_ = 0.0;        ///< path length over the samples update() saw [m]
  std::optional<Eigen::Vector2d> last_xy_;
  void drop_held();
  bool initiated_ = false;
  bool in_traversal_ = false;  ///< hold_initiation
  BodyDirection last_contact_ = BodyDirection::kNone;
  std::optional<int> last_move_world_;       ///< lambda quantised to a world axis (0:+X 1:+Y 2:-X 3:-Y)
  Eigen::Vector2d last_contact_world_ = Eigen::Vector2d::Zero();
  std::vector<FaceSample> face_;                       ///< face slabs of the current traversal (corner fill, face clip)
  std::optional<std::vector<FaceSample>> turned_face_;  ///< the previous face, if it ended in a turn
};

}  // namespace mapping_pcl
