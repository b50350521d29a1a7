//! The upload a mission list implies: the MAVLink frames a ground station and a vehicle that
//! do everything right exchange to transfer it (`mochi mission` runs them through the
//! monitor; the proxy tests replay them).

use super::mission::{Mission, MissionType};
use super::parse::{Config, RawReader};
use super::Frame;
use mavlink::dialects::ardupilotmega::{
    MavCmd, MavFrame, MavMessage, MavMissionResult, MavMissionType, MISSION_ACK_DATA, MISSION_COUNT_DATA,
    MISSION_ITEM_INT_DATA, MISSION_REQUEST_INT_DATA,
};
use mavlink::{MavHeader, MavlinkVersion};
use num_traits::FromPrimitive;

/// The ground station and vehicle of an upload trace: system and component ids.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ends {
    /// The ground station (QGroundControl's 255/190 by default).
    pub gcs: (u8, u8),
    /// The vehicle (1/1 by default).
    pub vehicle: (u8, u8),
}

impl Default for Ends {
    fn default() -> Self {
        Ends { gcs: (255, 190), vehicle: (1, 1) }
    }
}

/// The upload of `mission` as a ground station and a vehicle that do everything right run
/// it: MISSION_COUNT (GCS), then for each item MISSION_REQUEST_INT (vehicle) and
/// MISSION_ITEM_INT (GCS), then MISSION_ACK ACCEPTED (vehicle); for an empty list, COUNT 0 and
/// the ACK. MAVLink 2 frames, sequence numbers counting per sender, encoded by the `mavlink`
/// crate. The frames are read back with [`UploadTrace::frames`].
pub fn upload_trace(mission: &Mission, ends: Ends) -> UploadTrace {
    let mt = match mission.mission_type {
        MissionType::Mission => MavMissionType::MAV_MISSION_TYPE_MISSION,
        MissionType::Fence => MavMissionType::MAV_MISSION_TYPE_FENCE,
        MissionType::Rally => MavMissionType::MAV_MISSION_TYPE_RALLY,
    };
    let mut bytes = Vec::new();
    let (mut gseq, mut vseq) = (0u8, 0u8);
    let gcs = |seq: &mut u8| {
        let h = MavHeader { system_id: u32::from(ends.gcs.0), component_id: ends.gcs.1, sequence: *seq };
        *seq = seq.wrapping_add(1);
        h
    };
    let veh = |seq: &mut u8| {
        let h = MavHeader { system_id: u32::from(ends.vehicle.0), component_id: ends.vehicle.1, sequence: *seq };
        *seq = seq.wrapping_add(1);
        h
    };
    let (vs, vc) = ends.vehicle;
    let (gs, gc) = ends.gcs;
    let mut put = |h: MavHeader, m: MavMessage| {
        // Writing to a Vec cannot fail.
        let _ = mavlink::write_versioned_msg(&mut bytes, MavlinkVersion::V2, h, &m);
    };
    put(
        gcs(&mut gseq),
        MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
            count: mission.items.len() as u16,
            target_system: vs,
            target_component: vc,
            mission_type: mt,
            opaque_id: 0,
        }),
    );
    for it in &mission.items {
        put(
            veh(&mut vseq),
            MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
                seq: it.seq,
                target_system: gs,
                target_component: gc,
                mission_type: mt,
            }),
        );
        put(
            gcs(&mut gseq),
            MavMessage::MISSION_ITEM_INT(MISSION_ITEM_INT_DATA {
                param1: it.params[0],
                param2: it.params[1],
                param3: it.params[2],
                param4: it.params[3],
                x: it.x,
                y: it.y,
                z: it.z,
                seq: it.seq,
                // Both were checked against the dialect when the file was read.
                command: MavCmd::from_u16(it.command).unwrap_or_default(),
                target_system: vs,
                target_component: vc,
                frame: MavFrame::from_u8(it.frame).unwrap_or_default(),
                current: u8::from(it.current),
                autocontinue: u8::from(it.autocontinue),
                mission_type: mt,
            }),
        );
    }
    put(
        veh(&mut vseq),
        MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            target_system: gs,
            target_component: gc,
            mavtype: MavMissionResult::MAV_MISSION_ACCEPTED,
            mission_type: mt,
            opaque_id: 0,
        }),
    );
    UploadTrace { bytes }
}

/// The frames of an upload, encoded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UploadTrace {
    /// The frames back to back, as a raw MAVLink stream.
    pub bytes: Vec<u8>,
}

impl UploadTrace {
    /// The frames in order.
    pub fn frames(&self) -> impl Iterator<Item = Frame<'_>> {
        RawReader::new(&self.bytes, Config::default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mavio::mission::parse_mission;
    use mavlink::Message;

    #[test]
    fn the_upload_trace_is_count_requests_items_ack() {
        let f = parse_mission(
            "m.txt",
            "QGC WPL 110\n0 1 0 16 0 0 0 0 -35.36372 149.16523 584 1\n1 0 3 22 15 0 0 0 0 0 30 1\n",
        )
        .unwrap();
        let t = upload_trace(&f.missions[0], Ends::default());
        let ids: Vec<(u8, u32)> = t.frames().map(|f| (f.sysid, f.msgid)).collect();
        assert_eq!(ids, [(255, 44), (1, 51), (255, 73), (1, 51), (255, 73), (1, 47)]);
        let item = t.frames().nth(2).unwrap();
        let m = MavMessage::parse(MavlinkVersion::V2, item.msgid, item.payload).unwrap();
        let MavMessage::MISSION_ITEM_INT(d) = m else { panic!("{m:?}") };
        assert_eq!((d.x, d.y, d.z, d.seq), (-353_637_200, 1_491_652_300, 584.0, 0));
    }
}
