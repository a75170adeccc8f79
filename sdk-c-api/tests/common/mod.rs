pub mod c_layout;
