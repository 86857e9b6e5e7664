//! Reading URDF text with `urdf-rs`, with a check of the top element that the reader skips.

use crate::error::ModelError;

/// Parses URDF text into the reader's tree.
pub(crate) fn parse(urdf: &str) -> Result<urdf_rs::Robot, ModelError> {
    if let Some(name) = top_element(urdf)
        && name != "robot"
    {
        return Err(ModelError::Parse {
            message: format!("the top element is <{name}>, not <robot>"),
        });
    }
    urdf_rs::read_from_string(urdf).map_err(|e| ModelError::Parse {
        message: e.to_string(),
    })
}

/// The name of the first element, after the XML declaration, processing instructions,
/// comments and a document type; `None` when there is none to find (the reader then says
/// what is wrong).
fn top_element(text: &str) -> Option<&str> {
    let mut rest = text.trim_start_matches('\u{feff}');
    loop {
        rest = rest.trim_start();
        if let Some(after) = rest.strip_prefix("<?") {
            rest = &after[after.find("?>")? + 2..];
        } else if let Some(after) = rest.strip_prefix("<!--") {
            rest = &after[after.find("-->")? + 3..];
        } else if let Some(after) = rest.strip_prefix("<!") {
            rest = &after[after.find('>')? + 1..];
        } else {
            let after = rest.strip_prefix('<')?;
            let end = after
                .find(|c: char| c.is_whitespace() || c == '/' || c == '>')
                .unwrap_or(after.len());
            return Some(&after[..end]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::top_element;

    #[test]
    fn finds_the_top_element_past_the_prologue() {
        let text =
            "\u{feff}<?xml version=\"1.0\"?>\n<!-- a <robot> -->\n<!DOCTYPE x>\n<robot name=\"r\">";
        assert_eq!(top_element(text), Some("robot"));
        assert_eq!(top_element("<notrobot/>"), Some("notrobot"));
        assert_eq!(top_element("<!-- unterminated"), None);
        assert_eq!(top_element("plain text"), None);
        assert_eq!(top_element(""), None);
    }
}
