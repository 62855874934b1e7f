//! An action's server side on DDS, in every client's mapping: its three services
//! (`send_goal`, `cancel_goal`, `get_result`) are [`AnyServer`]s, its feedback and status
//! topics the node's publishers. The same parts, names and types as ros2-client's
//! `ActionServer`, which answers in one mapping only ([`crate::mapping`]).

use ros2_client::action::{
    FeedbackMessage, GetResultRequest, GetResultResponse, SendGoalRequest, SendGoalResponse,
};
use ros2_client::action_msgs::{CancelGoalRequest, CancelGoalResponse, GoalId, GoalStatusArray};
use ros2_client::{Message, MessageTypeName, Name, Node, NodeName, Publisher, QosProfile};

use crate::actions::ActionServices;
use crate::mapping::{AnyServer, Asker, SharedVendors};

/// Where an action's server lives: the node, its DDS participant and a DDS publisher in
/// it for the reply writers, and the participants' vendors.
pub struct Place<'a> {
    pub node: &'a mut Node,
    pub node_name: &'a NodeName,
    pub participant: &'a rustdds::DomainParticipant,
    pub writers: &'a rustdds::Publisher,
    pub vendors: SharedVendors,
}

pub struct AnyActionServer<G, R, F: serde::Serialize> {
    goals: AnyServer<SendGoalRequest<G>, SendGoalResponse>,
    cancels: AnyServer<CancelGoalRequest, CancelGoalResponse>,
    results: AnyServer<GetResultRequest, GetResultResponse<R>>,
    feedback: Publisher<FeedbackMessage<F>>,
    status: Publisher<GoalStatusArray>,
    name: String,
}

/// The QoS of an action's parts, as ROS 2's defaults have them.
pub struct ActionQos {
    pub services: QosProfile,
    pub feedback: QosProfile,
    pub status: QosProfile,
}

impl<G, R, F> AnyActionServer<G, R, F>
where
    G: Message + Clone + 'static,
    R: Message + Clone + 'static,
    F: Message + 'static,
{
    /// The action `<ns>/<action>` of type `<package>/action/<type_name>`.
    pub fn new(
        place: Place<'_>,
        ns: &str,
        action: &str,
        (package, type_name): (&str, &str),
        qos: &ActionQos,
    ) -> Result<AnyActionServer<G, R, F>, String> {
        let services = ActionServices::new(ns, action, place.node_name)?;
        let action_type = |part: &str| format!("{package}::action::dds_::{type_name}{part}");
        let goals = AnyServer::new(
            place.node,
            place.participant,
            place.writers,
            &services.send_goal,
            &action_type("_SendGoal"),
            &qos.services,
            place.vendors.clone(),
        )?;
        let cancels = AnyServer::new(
            place.node,
            place.participant,
            place.writers,
            &services.cancel_goal,
            "action_msgs::srv::dds_::CancelGoal",
            &qos.services,
            place.vendors.clone(),
        )?;
        let results = AnyServer::new(
            place.node,
            place.participant,
            place.writers,
            &services.get_result,
            &action_type("_GetResult"),
            &qos.services,
            place.vendors,
        )?;
        let dir = format!("{}/{action}/_action", ns.trim_end_matches('/'));
        let topic_name = |base: &str| {
            Name::new(&dir, base)
                .map(|n| n.to_dds_name("rt", place.node_name, ""))
                .map_err(|e| format!("{action}'s {base}: {e:?}"))
        };
        let create = |e: &dyn std::fmt::Debug| format!("{action}: {e:?}");
        let feedback_topic = place
            .participant
            .create_topic(
                topic_name("feedback")?,
                action_type("_FeedbackMessage_"),
                &rustdds::QosPolicies::from(&qos.feedback),
                rustdds::TopicKind::NoKey,
            )
            .map_err(|e| create(&e))?;
        let feedback = place
            .node
            .create_publisher(&feedback_topic, Some(qos.feedback.clone()))
            .map_err(|e| create(&e))?;
        let status_topic = place
            .participant
            .create_topic(
                topic_name("status")?,
                MessageTypeName::new("action_msgs", "GoalStatusArray").dds_msg_type(),
                &rustdds::QosPolicies::from(&qos.status),
                rustdds::TopicKind::NoKey,
            )
            .map_err(|e| create(&e))?;
        let status = place
            .node
            .create_publisher(&status_topic, Some(qos.status.clone()))
            .map_err(|e| create(&e))?;
        Ok(AnyActionServer {
            goals,
            cancels,
            results,
            feedback,
            status,
            name: format!("{}/{action}", ns.trim_end_matches('/')),
        })
    }

    /// The action's name (`/arm1/follow_joint_trajectory`).
    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn receive_goal(&self) -> Result<Option<(Asker, SendGoalRequest<G>)>, String> {
        self.goals.receive_request()
    }

    pub fn send_goal_response(&self, to: &Asker, resp: SendGoalResponse) -> Result<(), String> {
        self.goals.send_response(to, resp)
    }

    pub fn receive_cancel_request(&self) -> Result<Option<(Asker, CancelGoalRequest)>, String> {
        self.cancels.receive_request()
    }

    pub fn send_cancel_response(&self, to: &Asker, resp: CancelGoalResponse) -> Result<(), String> {
        self.cancels.send_response(to, resp)
    }

    pub fn receive_result_request(&self) -> Result<Option<(Asker, GetResultRequest)>, String> {
        self.results.receive_request()
    }

    pub fn send_result(&self, to: &Asker, resp: GetResultResponse<R>) -> Result<(), String> {
        self.results.send_response(to, resp)
    }

    pub fn send_feedback(&self, goal_id: GoalId, feedback: F) -> Result<(), String> {
        self.feedback
            .publish(FeedbackMessage { goal_id, feedback })
            .map_err(|e| format!("{:?}", e.forget_data()))
    }

    pub fn send_goal_statuses(&self, statuses: GoalStatusArray) -> Result<(), String> {
        self.status
            .publish(statuses)
            .map_err(|e| format!("{:?}", e.forget_data()))
    }
}
