//! The node's parameters, as every ROS 2 node offers them: the six `rcl_interfaces`
//! services under `<ns>/trol_a465/` (`ros2 param list`, `get`, `describe`, `dump`), each
//! answered in its client's mapping (mapping.rs) once the client can hear it (replies.rs).
//!
//! They say how the node was started (`port`, `rate`, `prefix`, `distro`, `one_goal`,
//! `use_sim_time`) and are read-only: a set is refused with what to do instead (restart the
//! node with the option), and nothing changes.

use std::time::Instant;

use ros2_client::parameters::raw::{
    ParameterDescriptor, ParameterType, ParameterValue, SetParametersResult,
};
use ros2_client::rcl_interfaces::{
    DescribeParametersRequest, DescribeParametersResponse, GetParameterTypesRequest,
    GetParameterTypesResponse, GetParametersRequest, GetParametersResponse, ListParametersRequest,
    ListParametersResponse, ListParametersResult, SetParametersAtomicallyResponse,
    SetParametersRequest, SetParametersResponse,
};
use ros2_client::{Message, Node, NodeName, QosProfile};

use crate::mapping::{AnyServer, SharedVendors};
use crate::replies::{Matches, Replies, Service};

/// One parameter's value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Bool(bool),
    Double(f64),
    Text(String),
}

/// One read-only parameter: its name, value, what it says, and the option that sets it.
#[derive(Clone, Debug, PartialEq)]
pub struct Declared {
    pub name: &'static str,
    pub value: Value,
    pub description: &'static str,
    pub option: &'static str,
}

impl Declared {
    fn kind(&self) -> u8 {
        match self.value {
            Value::Bool(_) => ParameterType::BOOL,
            Value::Double(_) => ParameterType::DOUBLE,
            Value::Text(_) => ParameterType::STRING,
        }
    }

    fn raw(&self) -> ParameterValue {
        let mut v = not_set();
        v.ptype = self.kind();
        match &self.value {
            Value::Bool(b) => v.boolean_value = *b,
            Value::Double(d) => v.double_value = *d,
            Value::Text(s) => v.string_value = s.clone(),
        }
        v
    }

    fn descriptor(&self) -> ParameterDescriptor {
        ParameterDescriptor {
            name: self.name.to_string(),
            r#type: self.kind(),
            description: self.description.to_string(),
            additional_constraints: format!("read-only: set by {}", self.option),
            read_only: true,
            dynamic_typing: false,
            floating_point_range: Vec::new(),
            integer_range: Vec::new(),
        }
    }
}

/// A value of no type: what a get of an undeclared name answers (as rclcpp does).
fn not_set() -> ParameterValue {
    ParameterValue {
        ptype: ParameterType::NOT_SET,
        boolean_value: false,
        int_value: 0,
        double_value: 0.0,
        string_value: String::new(),
        byte_array: Vec::new(),
        bool_array: Vec::new(),
        int_array: Vec::new(),
        double_array: Vec::new(),
        string_array: Vec::new(),
    }
}

/// The node's parameters and the answers to each of the six services.
#[derive(Clone, Debug, PartialEq)]
pub struct Params(pub Vec<Declared>);

impl Params {
    fn find(&self, name: &str) -> Option<&Declared> {
        self.0.iter().find(|d| d.name == name)
    }

    /// ListParameters: every name under one of `prefixes` (all where none is given). The
    /// names have no `.`, so `depth` changes nothing.
    pub fn list(&self, req: &ListParametersRequest) -> ListParametersResponse {
        let names = self
            .0
            .iter()
            .map(|d| d.name)
            .filter(|n| {
                req.prefixes.is_empty()
                    || req
                        .prefixes
                        .iter()
                        .any(|p| *n == p || n.starts_with(&format!("{p}.")))
            })
            .map(str::to_string)
            .collect();
        ListParametersResponse {
            result: ListParametersResult {
                names,
                prefixes: Vec::new(),
            },
        }
    }

    /// GetParameters: a value per name asked, of no type for a name not declared.
    pub fn get(&self, req: &GetParametersRequest) -> GetParametersResponse {
        GetParametersResponse {
            values: req
                .names
                .iter()
                .map(|n| self.find(n).map_or_else(not_set, Declared::raw))
                .collect(),
        }
    }

    /// GetParameterTypes: a type per name asked, NOT_SET for a name not declared.
    pub fn types(&self, req: &GetParameterTypesRequest) -> GetParameterTypesResponse {
        GetParameterTypesResponse {
            values: req
                .names
                .iter()
                .map(|n| self.find(n).map_or(ParameterType::NOT_SET, Declared::kind))
                .collect(),
        }
    }

    /// DescribeParameters: a descriptor per name; none at all where a name is not declared
    /// (as rclcpp answers, its node allowing no undeclared parameters).
    pub fn describe(&self, req: &DescribeParametersRequest) -> DescribeParametersResponse {
        let found: Option<Vec<_>> = req
            .names
            .iter()
            .map(|n| self.find(n).map(Declared::descriptor))
            .collect();
        DescribeParametersResponse {
            values: found.unwrap_or_default(),
        }
    }

    /// Why a set of `name` is refused (every parameter is read-only).
    fn refusal(&self, name: &str) -> SetParametersResult {
        SetParametersResult {
            successful: false,
            reason: match self.find(name) {
                Some(d) => format!(
                    "parameter '{name}' is read-only: restart trol-ros2 with {} to change it",
                    d.option
                ),
                None => format!(
                    "parameter '{name}' is not declared (this node has {})",
                    self.0.iter().map(|d| d.name).collect::<Vec<_>>().join(", ")
                ),
            },
        }
    }

    /// SetParameters: each refused, nothing changed.
    pub fn set(&self, req: &SetParametersRequest) -> SetParametersResponse {
        SetParametersResponse {
            results: req
                .parameter
                .iter()
                .map(|p| self.refusal(&p.name))
                .collect(),
        }
    }

    /// SetParametersAtomically: refused as a whole, nothing changed.
    pub fn set_atomically(&self, req: &SetParametersRequest) -> SetParametersAtomicallyResponse {
        SetParametersAtomicallyResponse {
            result: match req.parameter.first() {
                Some(p) => self.refusal(&p.name),
                None => SetParametersResult {
                    successful: false,
                    reason: "no parameter given".into(),
                },
            },
        }
    }
}

/// One parameter service: its server and its replies not yet heard.
struct One<Req, Resp> {
    server: AnyServer<Req, Resp>,
    replies: Replies<Resp>,
}

impl<Req: Message, Resp: Message> One<Req, Resp> {
    fn new(at: &mut Place<'_>, base: &str, dds_type: &str) -> Result<One<Req, Resp>, String> {
        let node_path = format!("{}/{base}", at.node_name.base_name());
        let topics = Service::new(at.ns, &node_path, at.node_name)?;
        let server = AnyServer::new(
            at.node,
            at.participant,
            at.writers,
            &topics,
            &format!("rcl_interfaces::srv::dds_::{dds_type}"),
            at.qos,
            at.vendors.clone(),
        )?;
        Ok(One {
            server,
            replies: Replies::new(topics),
        })
    }

    /// Answer what came with `answer`, and send what can be heard.
    fn serve(&mut self, matches: &Matches, answer: impl Fn(&Req) -> Resp) {
        let now = Instant::now();
        while let Some((asker, req)) = crate::mapping::next(|| self.server.receive_request()) {
            self.replies.push(asker, answer(&req), now);
        }
        let server = &self.server;
        self.replies.flush(
            now,
            |s| matches.hear(s),
            |asker, reply| {
                if let Err(e) = server.send_response(asker, reply) {
                    tracing::warn!("a parameter service's response: {e}");
                }
            },
        );
    }
}

/// Where the services are made: the node, its DDS participant and reply writers' publisher.
pub struct Place<'a> {
    pub node: &'a mut Node,
    pub node_name: &'a NodeName,
    pub ns: &'a str,
    pub participant: &'a rustdds::DomainParticipant,
    pub writers: &'a rustdds::Publisher,
    pub qos: &'a QosProfile,
    pub vendors: SharedVendors,
}

/// The six parameter services of a node.
pub struct Services {
    params: Params,
    list: One<ListParametersRequest, ListParametersResponse>,
    get: One<GetParametersRequest, GetParametersResponse>,
    types: One<GetParameterTypesRequest, GetParameterTypesResponse>,
    describe: One<DescribeParametersRequest, DescribeParametersResponse>,
    set: One<SetParametersRequest, SetParametersResponse>,
    set_atomically: One<SetParametersRequest, SetParametersAtomicallyResponse>,
}

impl Services {
    pub fn new(mut at: Place<'_>, params: Params) -> Result<Services, String> {
        Ok(Services {
            params,
            list: One::new(&mut at, "list_parameters", "ListParameters")?,
            get: One::new(&mut at, "get_parameters", "GetParameters")?,
            types: One::new(&mut at, "get_parameter_types", "GetParameterTypes")?,
            describe: One::new(&mut at, "describe_parameters", "DescribeParameters")?,
            set: One::new(&mut at, "set_parameters", "SetParameters")?,
            set_atomically: One::new(
                &mut at,
                "set_parameters_atomically",
                "SetParametersAtomically",
            )?,
        })
    }

    /// Answer every request that came.
    pub fn serve(&mut self, matches: &Matches) {
        let p = &self.params;
        self.list.serve(matches, |r| p.list(r));
        self.get.serve(matches, |r| p.get(r));
        self.types.serve(matches, |r| p.types(r));
        self.describe.serve(matches, |r| p.describe(r));
        self.set.serve(matches, |r| p.set(r));
        self.set_atomically.serve(matches, |r| p.set_atomically(r));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ros2_client::parameters::raw::Parameter;

    fn params() -> Params {
        Params(vec![
            Declared {
                name: "rate",
                value: Value::Double(50.0),
                description: "joint_states' rate, Hz",
                option: "--rate",
            },
            Declared {
                name: "port",
                value: Value::Text("sim".into()),
                description: "the arm's port",
                option: "--port",
            },
            Declared {
                name: "one_goal",
                value: Value::Bool(false),
                description: "a second goal is refused",
                option: "--one-goal",
            },
        ])
    }

    #[test]
    fn list_get_and_describe_answer_as_rclcpp_does() {
        let p = params();
        let all = p.list(&ListParametersRequest {
            prefixes: vec![],
            depth: 0,
        });
        assert_eq!(all.result.names, ["rate", "port", "one_goal"]);
        let some = p.list(&ListParametersRequest {
            prefixes: vec!["port".into()],
            depth: 0,
        });
        assert_eq!(some.result.names, ["port"]);
        let got = p.get(&GetParametersRequest {
            names: vec!["port".into(), "nothing".into(), "rate".into()],
        });
        assert_eq!(got.values.len(), 3);
        assert_eq!(
            (got.values[0].ptype, got.values[0].string_value.as_str()),
            (ParameterType::STRING, "sim")
        );
        assert_eq!(got.values[1].ptype, ParameterType::NOT_SET);
        assert_eq!(
            (got.values[2].ptype, got.values[2].double_value),
            (ParameterType::DOUBLE, 50.0)
        );
        let types = p.types(&GetParameterTypesRequest {
            names: vec!["one_goal".into(), "x".into()],
        });
        assert_eq!(types.values, [ParameterType::BOOL, ParameterType::NOT_SET]);
        let d = p.describe(&DescribeParametersRequest {
            names: vec!["rate".into()],
        });
        assert!(d.values[0].read_only && d.values[0].additional_constraints.contains("--rate"));
        let none = p.describe(&DescribeParametersRequest {
            names: vec!["rate".into(), "x".into()],
        });
        assert!(none.values.is_empty());
    }

    #[test]
    fn every_set_is_refused_with_what_to_do_and_nothing_changes() {
        let p = params();
        let before = p.clone();
        let value = |d: f64| {
            let mut v = not_set();
            v.ptype = ParameterType::DOUBLE;
            v.double_value = d;
            v
        };
        let req = SetParametersRequest {
            parameter: vec![
                Parameter {
                    name: "rate".into(),
                    value: value(10.0),
                },
                Parameter {
                    name: "speed".into(),
                    value: value(1.0),
                },
            ],
        };
        let r = p.set(&req);
        assert!(r.results.iter().all(|x| !x.successful));
        assert!(
            r.results[0]
                .reason
                .contains("restart trol-ros2 with --rate")
        );
        assert!(r.results[1].reason.contains("not declared"));
        assert!(!p.set_atomically(&req).result.successful);
        assert_eq!(p, before);
    }
}
