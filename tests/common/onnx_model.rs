//! Tiny ONNX networks written from the test (tract's own protobuf types, encoded with
//! prost): the shapes, metadata and values a hostile or broken file would have, without
//! shipping binary fixtures.

use prost::Message;
use tract_onnx::pb::{
    tensor_shape_proto::{dimension, Dimension},
    type_proto, GraphProto, ModelProto, NodeProto, OperatorSetIdProto, StringStringEntryProto,
    TensorProto, TensorShapeProto, TypeProto, ValueInfoProto,
};

const FLOAT: i32 = 1;

fn value(name: &str, dims: &[i64]) -> ValueInfoProto {
    ValueInfoProto {
        name: name.into(),
        r#type: Some(TypeProto {
            value: Some(type_proto::Value::TensorType(type_proto::Tensor {
                elem_type: FLOAT,
                shape: Some(TensorShapeProto {
                    dim: dims
                        .iter()
                        // A negative dimension is symbolic (`batch`), as exporters write
                        // a dynamic batch axis.
                        .map(|&d| Dimension {
                            value: Some(if d < 0 {
                                dimension::Value::DimParam("batch".into())
                            } else {
                                dimension::Value::DimValue(d)
                            }),
                            ..Default::default()
                        })
                        .collect(),
                }),
            })),
            ..Default::default()
        }),
        ..Default::default()
    }
}

/// A float network: `inputs` (name, shape); each output `name = input · W` (MatMul with a
/// constant `W` of `fill` values, shape [last dim of the input, width]); metadata
/// properties as given.
pub struct Network<'a> {
    pub inputs: Vec<(&'a str, Vec<i64>)>,
    /// (output name, input it multiplies, width, fill value of its weights)
    pub outputs: Vec<(&'a str, &'a str, i64, f32)>,
    pub metadata: Vec<(&'a str, String)>,
}

impl Network<'_> {
    pub fn bytes(&self) -> Vec<u8> {
        let mut graph = GraphProto {
            name: "test".into(),
            ..Default::default()
        };
        for (name, dims) in &self.inputs {
            graph.input.push(value(name, dims));
        }
        for (name, input, width, fill) in &self.outputs {
            let rows = self
                .inputs
                .iter()
                .find(|(n, _)| n == input)
                .map(|(_, d)| *d.last().unwrap())
                .unwrap();
            let w = format!("{name}_weights");
            graph.initializer.push(TensorProto {
                name: w.clone(),
                dims: vec![rows, *width],
                data_type: FLOAT,
                float_data: vec![*fill; (rows * width) as usize],
                ..Default::default()
            });
            graph.node.push(NodeProto {
                name: format!("{name}_matmul"),
                op_type: "MatMul".into(),
                input: vec![input.to_string(), w],
                output: vec![name.to_string()],
                ..Default::default()
            });
            let batch = self
                .inputs
                .iter()
                .find(|(n, _)| n == input)
                .map_or(1, |(_, d)| d[0]);
            graph.output.push(value(name, &[batch, *width]));
        }
        ModelProto {
            ir_version: 8,
            opset_import: vec![OperatorSetIdProto {
                domain: String::new(),
                version: 17,
            }],
            graph: Some(graph),
            metadata_props: self
                .metadata
                .iter()
                .map(|(k, v)| StringStringEntryProto {
                    key: k.to_string(),
                    value: v.clone(),
                })
                .collect(),
            ..Default::default()
        }
        .encode_to_vec()
    }
}
