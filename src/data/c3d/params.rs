//! A minimal reader of a C3D file's parameter section, for the parameters `c3dio` 0.8
//! parses but does not hand over (`FORCE_PLATFORM:CAL_MATRIX`) or refuses before saying
//! which value it refused (`FORCE_PLATFORM:TYPE` beyond 1–4).
//!
//! Layout (C3D user guide, "The parameter section"): the header's first byte is the
//! 1-based block (512 bytes) of the parameter section, whose fourth byte is the processor
//! (84 Intel, 85 DEC, 86 MIPS). Records follow from byte 4: name length (i8, negative when
//! locked; 0 ends the section), group id (i8, negative for a group, positive for a
//! parameter of that group), the name, an i16 offset to the next record counted from the
//! offset's first byte (0 ends the section), then for a parameter its type (−1 char,
//! 1 byte, 2 i16, 4 f32), dimension count, dimensions (u8 each), and data (first index
//! fastest).

/// Processor (byte order and float format) of a C3D file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Processor {
    Intel,
    Dec,
    Mips,
}

/// Why a C3D file's parameter section cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(super) enum ParameterSectionError {
    /// The file has no bytes.
    #[error("the file is empty")]
    Empty,
    /// The header's pointer to the parameter section is 0.
    #[error("the header's first byte (parameter block) is 0")]
    ZeroBlock,
    /// The processor byte is none of the three C3D knows.
    #[error("processor type {code} is not 84, 85 or 86")]
    Processor {
        /// The byte found.
        code: u8,
    },
    /// The file ends before the block the header points to.
    #[error("the file ends before the parameter block {block}")]
    NoBlock {
        /// The parameter section's block (1-based, 512 bytes each).
        block: usize,
    },
    /// A record is cut off by the end of the file.
    #[error("the parameter section ends inside a record")]
    Truncated,
    /// A parameter's data type is unknown or its data run past the end of the file.
    #[error("{group}:{name} has data type {data_type} or runs past the file")]
    Data {
        /// The parameter's group.
        group: String,
        /// The parameter's name.
        name: String,
        /// Its data type byte (−1 char, 1 byte, 2 i16, 4 f32).
        data_type: i8,
    },
}

/// One parameter's raw values.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct RawParameter {
    /// Dimensions (first varies fastest); empty for a scalar.
    pub dims: Vec<usize>,
    /// Values as numbers (characters as their byte values).
    pub values: Vec<f64>,
}

fn i16_at(b: &[u8], at: usize, p: Processor) -> Option<i16> {
    let x = [*b.get(at)?, *b.get(at + 1)?];
    Some(match p {
        Processor::Mips => i16::from_be_bytes(x),
        _ => i16::from_le_bytes(x),
    })
}

fn f32_at(b: &[u8], at: usize, p: Processor) -> Option<f32> {
    let x = [
        *b.get(at)?,
        *b.get(at + 1)?,
        *b.get(at + 2)?,
        *b.get(at + 3)?,
    ];
    Some(match p {
        Processor::Intel => f32::from_le_bytes(x),
        Processor::Mips => f32::from_be_bytes(x),
        // VAX F: 16-bit little-endian words in the opposite order, exponent bias 128
        // with the hidden bit at 0.5: the IEEE reading of the swapped words is 4× the value.
        Processor::Dec => f32::from_le_bytes([x[2], x[3], x[0], x[1]]) / 4.0,
    })
}

/// The parameter `group:name` (case-insensitive) of the C3D file `bytes`, `Ok(None)` if
/// absent; `Err` with the reason if the parameter section is malformed.
pub(super) fn find(
    bytes: &[u8],
    group: &str,
    name: &str,
) -> Result<Option<RawParameter>, ParameterSectionError> {
    let block = *bytes.first().ok_or(ParameterSectionError::Empty)? as usize;
    if block == 0 {
        return Err(ParameterSectionError::ZeroBlock);
    }
    let start = (block - 1) * 512;
    let p = match bytes.get(start + 3) {
        Some(84) => Processor::Intel,
        Some(85) => Processor::Dec,
        Some(86) => Processor::Mips,
        Some(&code) => return Err(ParameterSectionError::Processor { code }),
        None => return Err(ParameterSectionError::NoBlock { block }),
    };
    let short = || ParameterSectionError::Truncated;
    // First pass: group ids by name; parameters are matched by (group id, name).
    let mut records = Vec::new();
    let mut at = start + 4;
    while let Some(&len) = bytes.get(at) {
        let len = (len as i8).unsigned_abs() as usize;
        if len == 0 {
            break;
        }
        let id = *bytes.get(at + 1).ok_or_else(short)? as i8;
        let rec_name = bytes.get(at + 2..at + 2 + len).ok_or_else(short)?;
        let rec_name = String::from_utf8_lossy(rec_name).to_ascii_uppercase();
        let off_at = at + 2 + len;
        let next = i16_at(bytes, off_at, p).ok_or_else(short)?;
        records.push((id, rec_name, off_at + 2));
        if next <= 0 {
            break;
        }
        at = off_at + next as usize;
    }
    let gname = group.to_ascii_uppercase();
    let Some(gid) = records
        .iter()
        .find(|(id, n, _)| *id < 0 && *n == gname)
        .map(|(id, _, _)| -*id)
    else {
        return Ok(None);
    };
    let pname = name.to_ascii_uppercase();
    let Some(&(_, _, body)) = records.iter().find(|(id, n, _)| *id == gid && *n == pname) else {
        return Ok(None);
    };
    let ty = *bytes.get(body).ok_or_else(short)? as i8;
    let nd = *bytes.get(body + 1).ok_or_else(short)? as usize;
    let dims: Vec<usize> = bytes
        .get(body + 2..body + 2 + nd)
        .ok_or_else(short)?
        .iter()
        .map(|&d| d as usize)
        .collect();
    let count: usize = dims.iter().product();
    let data = body + 2 + nd;
    let values = (0..count)
        .map(|k| match ty {
            -1 | 1 => bytes.get(data + k).map(|&b| b as f64),
            2 => i16_at(bytes, data + 2 * k, p).map(f64::from),
            4 => f32_at(bytes, data + 4 * k, p).map(f64::from),
            _ => None,
        })
        .collect::<Option<Vec<f64>>>()
        .ok_or_else(|| ParameterSectionError::Data {
            group: group.to_string(),
            name: name.to_string(),
            data_type: ty,
        })?;
    Ok(Some(RawParameter { dims, values }))
}
