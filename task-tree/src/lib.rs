//! TCA task trees and temporal constraints: pure bookkeeping, no I/O.
