//! Imaging Sensor Manager: virtual Erim and Perceptron laser rangefinders.
