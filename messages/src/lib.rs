//! TCA wire protocol: envelopes, message classes, data formats and the codec.
